// libcore/inpaint, the 2-D methods: OpenCV Telea/NS and the thesis §5.2 template method, on
// images built here with known answers (constant images, a texture seen shifted by a partner).
#include <gtest/gtest.h>

#include <cmath>
#include <cstdint>
#include <cstdlib>

#include "base/error.h"
#include "inpaint/inpaint.h"

namespace mvtm {
namespace {

// A deterministic texture with no repeats at the scales the templates see: 8-bit values from an
// integer hash of (x, y) in scene coordinates.
float Texture(int x, int y, int c) {
  uint32_t h = uint32_t(x) * 73856093u ^ uint32_t(y) * 19349663u ^ uint32_t(c + 1) * 83492791u;
  h ^= h >> 13;
  h *= 0x5bd1e995u;
  h ^= h >> 15;
  return float(h % 256);
}

// The scene seen by a camera whose pixel (0, 0) is scene point (ox, oy).
Image SceneView(int w, int h, int ox, int oy, int channels = 3) {
  Image im(w, h, channels, 8);
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x)
      for (int c = 0; c < channels; ++c) im.at(x, y, c) = Texture(x + ox, y + oy, c);
  return im;
}

Image Square(int w, int h, int x0, int y0, int side, int channels = 1, float value = 255) {
  Image m(w, h, channels, 8);
  for (int y = y0; y < y0 + side; ++y)
    for (int x = x0; x < x0 + side; ++x) m.at(x, y, channels - 1) = value;
  return m;
}

bool InSquare(int x, int y, int x0, int y0, int side) {
  return x >= x0 && y >= y0 && x < x0 + side && y < y0 + side;
}

TEST(InpaintOpenCv, ConstantImageGivesTheConstantBack) {
  // Navier–Stokes of a constant image is exactly the constant, for 8-bit RGB (whole), 16-bit
  // grey and float grey (channel by channel). OpenCV's Telea adds its gradient term, a value in
  // [−√2, √2] in sample units, and 0.5 before rounding: within 2 of the constant on 8 and 16
  // bits (on float images that is no bound at all: see inpaint.h).
  struct C {
    int channels, bits;
    float value;
  };
  for (C c : {C{3, 8, 137}, C{1, 16, 40000}, C{1, 32, 0.375f}})
    for (auto method : {OpenCvInpaintMethod::kNs, OpenCvInpaintMethod::kTelea}) {
      const bool telea = method == OpenCvInpaintMethod::kTelea;
      if (telea && c.bits == 32) continue;
      Image im(40, 30, c.channels, c.bits, c.value);
      Inpainted r = InpaintOpenCv(im, Square(40, 30, 12, 8, 10), method, 3);
      const double tolerance = telea ? 2 : c.bits == 32 ? 1e-6 : 0;
      for (size_t i = 0; i < im.data.size(); ++i)
        ASSERT_NEAR(r.image.data[i], c.value, tolerance) << c.bits << " " << telea << " " << i;
      EXPECT_EQ(r.counts.masked, 100u);
      EXPECT_EQ(r.counts.two_d, 100u);
    }
}

TEST(InpaintOpenCv, OnlyMaskedColourPixelsChange) {
  Image im = SceneView(40, 30, 0, 0, 4);  // RGBA: alpha is never touched
  // The mask as RGB with only blue set: any non-zero channel marks the pixel.
  Image mask = Square(40, 30, 5, 6, 9, 3, 1);
  Inpainted r = InpaintOpenCv(im, mask, OpenCvInpaintMethod::kTelea, 3);
  ASSERT_EQ(r.image.channels, 4);
  ASSERT_EQ(r.provenance.channels, 1);
  size_t changed = 0;
  for (int y = 0; y < 30; ++y)
    for (int x = 0; x < 40; ++x) {
      const bool in = InSquare(x, y, 5, 6, 9);
      EXPECT_EQ(r.provenance.at(x, y), in ? kProvenance2d : kProvenanceOriginal);
      EXPECT_EQ(r.image.at(x, y, 3), im.at(x, y, 3));
      for (int c = 0; c < 3; ++c) {
        if (!in) {
          ASSERT_EQ(r.image.at(x, y, c), im.at(x, y, c)) << x << "," << y;
        }
        changed += r.image.at(x, y, c) != im.at(x, y, c);
      }
    }
  EXPECT_GT(changed, 81u);  // a random texture is not reproduced by diffusion
  EXPECT_EQ(r.counts.masked, 81u);
  EXPECT_EQ(r.counts.two_d, 81u);
}

TEST(Inpaint, EmptyMaskCopiesTheImage) {
  Image im = SceneView(20, 10, 3, 4);
  Image empty(20, 10, 1, 8);
  Image partner = SceneView(20, 10, 0, 0);
  for (const Inpainted& r : {InpaintOpenCv(im, empty, OpenCvInpaintMethod::kNs, 3),
                             InpaintPatch2d(im, empty, {&partner}, 3)}) {
    EXPECT_EQ(r.image.data, im.data);
    EXPECT_EQ(r.provenance.data, std::vector<float>(200, kProvenanceOriginal));
    EXPECT_EQ(r.counts.masked + r.counts.partners + r.counts.two_d, 0u);
  }
}

TEST(Inpaint, MaskOfAnotherSizeIsAnError) {
  Image im(8, 6, 3, 8);
  try {
    InpaintOpenCv(im, Image(6, 8, 1, 8, 255), OpenCvInpaintMethod::kTelea, 3);
    ADD_FAILURE() << "no error";
  } catch (const Error& e) {
    EXPECT_EQ(std::string(e.what()), "mask is 6x8, image is 8x6");
  }
  try {
    CheckMaskSize(im, Image(8, 5, 1, 8), "masks/a.png");
    ADD_FAILURE() << "no error";
  } catch (const Error& e) {
    EXPECT_EQ(std::string(e.what()), "masks/a.png: mask is 8x5, image is 8x6");
  }
}

TEST(DilateMask, DiskOfTheRadius) {
  // OpenCV's elliptical structuring elements (imgproc's getStructuringElement, MORPH_ELLIPSE):
  //   r=1: .X.    r=2: ..X..
  //        XXX         XXXXX
  //        .X.         XXXXX
  //                    XXXXX
  //                    ..X..
  Image point(9, 9, 2, 8);
  point.at(4, 4, 1) = 7;  // set through the second channel
  Image d0 = DilateMask(point, 0), d1 = DilateMask(point, 1), d2 = DilateMask(point, 2);
  ASSERT_EQ(d1.channels, 1);
  for (int y = 0; y < 9; ++y)
    for (int x = 0; x < 9; ++x) {
      const int dx = std::abs(x - 4), dy = std::abs(y - 4);
      EXPECT_EQ(d0.at(x, y), dx + dy == 0 ? 255 : 0);
      EXPECT_EQ(d1.at(x, y), dx + dy <= 1 ? 255 : 0) << x << "," << y;
      EXPECT_EQ(d2.at(x, y), (dx <= 2 && dy <= 1) || (dx == 0 && dy == 2) ? 255 : 0)
          << x << "," << y;
    }
}

TEST(InpaintPatch2d, CopiesTheBlobFromTheShiftedPartner) {
  // The image sees the scene from (0, 0), a "vehicle" (constant grey) hides a 10×10 square; the
  // partner sees the same scene from (5, 3). The templates around the blob match the partner
  // exactly 5 left and 3 up, so the blob gets the scene back exactly.
  const int w = 64, h = 48, x0 = 25, y0 = 18, side = 10;
  Image truth = SceneView(w, h, 0, 0), im = truth;
  for (int y = y0; y < y0 + side; ++y)
    for (int x = x0; x < x0 + side; ++x)
      for (int c = 0; c < 3; ++c) im.at(x, y, c) = 128;
  Image noise(w, h, 3, 8);
  for (size_t i = 0; i < noise.data.size(); ++i) noise.data[i] = float((i * 7919) % 251);
  Image partner = SceneView(w, h, 5, 3);
  // Rank 1 is unrelated noise, rank 2 the real partner: provenance 2.
  Inpainted r = InpaintPatch2d(im, Square(w, h, x0, y0, side), {&noise, &partner}, 3);
  EXPECT_EQ(r.image.data, truth.data);
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x)
      ASSERT_EQ(r.provenance.at(x, y), InSquare(x, y, x0, y0, side) ? 2 : kProvenanceOriginal);
  EXPECT_EQ(r.counts.masked, 100u);
  EXPECT_EQ(r.counts.partners, 100u);
  EXPECT_EQ(r.counts.two_d, 0u);
}

TEST(InpaintPatch2d, GreyAndSixteenBitsOnTheEightBitScale) {
  // A 16-bit grey image copies from an 8-bit RGB partner: the mean of RGB, times 257.
  const int w = 64, h = 48, x0 = 25, y0 = 18, side = 10;
  Image rgb = SceneView(w, h, 0, 0);
  Image im(w, h, 1, 16);
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x)
      im.at(x, y) =
          std::nearbyint((rgb.at(x, y, 0) + rgb.at(x, y, 1) + rgb.at(x, y, 2)) / 3.f * 257);
  Image truth = im;
  for (int y = y0; y < y0 + side; ++y)
    for (int x = x0; x < x0 + side; ++x) im.at(x, y) = 0;
  Image partner = SceneView(w, h, -4, 2);
  Inpainted r = InpaintPatch2d(im, Square(w, h, x0, y0, side), {&partner}, 3);
  EXPECT_EQ(r.image.data, truth.data);
  EXPECT_EQ(r.counts.partners, 100u);
}

TEST(InpaintPatch2d, NoPartnerOrNoTemplateFallsBackToTelea) {
  Image im = SceneView(30, 20, 0, 0);
  Image partner = SceneView(30, 20, 1, 1);
  Image full(30, 20, 1, 8, 255);
  // No partner: exactly Telea.
  Image sq = Square(30, 20, 10, 5, 6);
  Inpainted a = InpaintPatch2d(im, sq, {}, 3),
            b = InpaintOpenCv(im, sq, OpenCvInpaintMethod::kTelea, 3);
  EXPECT_EQ(a.image.data, b.image.data);
  EXPECT_EQ(a.provenance.data, b.provenance.data);
  EXPECT_EQ(a.counts.two_d, 36u);
  // A blob covering the whole image has no room for a template: Telea, with a partner too.
  for (const Inpainted& r :
       {InpaintPatch2d(im, full, {}, 3), InpaintPatch2d(im, full, {&partner}, 3)}) {
    EXPECT_EQ(r.provenance.data, std::vector<float>(600, kProvenance2d));
    EXPECT_EQ(r.counts.masked, 600u);
    EXPECT_EQ(r.counts.two_d, 600u);
    EXPECT_EQ(r.counts.partners, 0u);
  }
}

}  // namespace
}  // namespace mvtm
