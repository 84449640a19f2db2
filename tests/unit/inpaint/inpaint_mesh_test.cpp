// libcore/inpaint, the 3-D method (thesis §5.3): hand-built planes seen by cameras looking down
// +z, partners of constant colour, so every masked pixel has one right answer: the partner's
// colour, the vertex colour, the sky from the partner, or the black background.
#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <memory>

#include "base/error.h"
#include "inpaint/inpaint.h"
#include "render/context.h"

namespace mvtm {
namespace {

// The test program's one GL context (render/context.h: one per process), made on first use.
void NeedGl() { static const std::unique_ptr<GlContext> context = GlContext::Create(); }

constexpr int kW = 64, kH = 48;
const std::array<uint8_t, 3> kVertexColour = {10, 200, 30};
const std::array<float, 3> kPartnerColour = {90, 120, 150};

// f = 50 px: a plane at z = 10 spans 25 px per 5 units from the principal point.
Camera Cam() { return ParseCameraSpec("PINHOLE 64 48 50 50 32 24"); }

// The square [−s, s]² at z = 10 as two triangles of one vertex colour.
Mesh Plane(double s) {
  Mesh m;
  m.vertices = {{-s, -s, 10}, {s, -s, 10}, {-s, s, 10}, {s, s, 10}};
  m.colors.assign(4, kVertexColour);
  m.faces = {{0, 1, 3}, {0, 3, 2}};
  return m;
}

View LookingDownZ(const Eigen::Vector3d& centre) {
  return {Cam(), Rigid3d(Eigen::Quaterniond::Identity(), -centre)};
}

Image Pattern(int channels = 3, int bits = 8) {
  Image im(kW, kH, channels, bits);
  for (int y = 0; y < kH; ++y)
    for (int x = 0; x < kW; ++x)
      for (int c = 0; c < channels; ++c) im.at(x, y, c) = float((x * 37 + y * 11 + c * 71) % 256);
  return im;
}

Image ConstantColour() {
  Image im(kW, kH, 3, 8);
  for (size_t p = 0; p < im.pixels(); ++p)
    for (size_t c = 0; c < 3; ++c) im.data[p * 3 + c] = kPartnerColour[c];
  return im;
}

Image Square(int x0, int y0, int side) {
  Image m(kW, kH, 1, 8);
  for (int y = y0; y < y0 + side; ++y)
    for (int x = x0; x < x0 + side; ++x) m.at(x, y) = 255;
  return m;
}

TEST(InpaintThroughMesh, PartnerOfAConstantPlaneGivesItsColourExactly) {
  NeedGl();
  Renderer r(Plane(50));
  const Image colour = ConstantColour();
  const Image depth(kW, kH, 1, 32, 10.f);  // the plane z = 10 seen straight on
  Projector p{LookingDownZ({1, 0.5, 0}), &colour, &depth, nullptr};
  const Image im = Pattern();
  Inpainted out =
      InpaintThroughMesh(r, LookingDownZ({0, 0, 0}), im, Square(20, 15, 12), {p}, 0.005);
  for (int y = 0; y < kH; ++y)
    for (int x = 0; x < kW; ++x) {
      const bool in = x >= 20 && x < 32 && y >= 15 && y < 27;
      ASSERT_EQ(out.provenance.at(x, y), in ? 1 : kProvenanceOriginal) << x << "," << y;
      for (int c = 0; c < 3; ++c)
        ASSERT_EQ(out.image.at(x, y, c), in ? kPartnerColour[size_t(c)] : im.at(x, y, c))
            << x << "," << y << " " << c;
    }
  EXPECT_EQ(out.counts.masked, 144u);
  EXPECT_EQ(out.counts.partners, 144u);
}

TEST(InpaintThroughMesh, SixteenBitsAndFloatGreyOnTheirOwnScale) {
  NeedGl();
  // Grey takes the mean of RGB (120) on the 8-bit scale: ×257 for 16 bits, ÷255 for float.
  Renderer r(Plane(50));
  const Image colour = ConstantColour();
  const Image depth(kW, kH, 1, 32, 10.f);
  Projector p{LookingDownZ({0, 0, 0}), &colour, &depth, nullptr};
  for (int bits : {16, 32}) {
    const Image im = Pattern(2, bits);  // grey + alpha: alpha keeps its values
    Inpainted out = InpaintThroughMesh(r, LookingDownZ({0, 0, 0}), im, Square(5, 5, 4), {p}, 0);
    if (bits == 16)
      EXPECT_EQ(out.image.at(6, 6, 0), 120.f * 257);
    else
      EXPECT_FLOAT_EQ(out.image.at(6, 6, 0), 120.f / 255.f);
    EXPECT_EQ(out.image.at(6, 6, 1), im.at(6, 6, 1));
    EXPECT_EQ(out.image.at(9, 9, 0), im.at(9, 9, 0));
  }
}

TEST(InpaintThroughMesh, MaskedPartnerFallsBackToVertexColour) {
  NeedGl();
  Renderer r(Plane(50));
  const Image colour = ConstantColour();
  const Image depth(kW, kH, 1, 32, 10.f);
  const Image all_masked(kW, kH, 1, 8, 255);
  Projector p{LookingDownZ({1, 0.5, 0}), &colour, &depth, &all_masked};
  Inpainted out =
      InpaintThroughMesh(r, LookingDownZ({0, 0, 0}), Pattern(), Square(20, 15, 12), {p}, 0.005);
  for (int y = 15; y < 27; ++y)
    for (int x = 20; x < 32; ++x) {
      ASSERT_EQ(out.provenance.at(x, y), kProvenanceVertex);
      for (int c = 0; c < 3; ++c) ASSERT_EQ(out.image.at(x, y, c), kVertexColour[size_t(c)]);
    }
  EXPECT_EQ(out.counts.vertex, 144u);
}

TEST(InpaintThroughMesh, FullMaskWithoutPartnersIsVertexColourElseBackground) {
  NeedGl();
  // The plane ±5 at z = 10 covers the columns within 25 px of the centre, not the image's edges.
  Renderer r(Plane(5));
  Inpainted out = InpaintThroughMesh(r, LookingDownZ({0, 0, 0}), Pattern(),
                                     Image(kW, kH, 1, 8, 255), {}, 0.005);
  EXPECT_EQ(out.provenance.at(32, 24), kProvenanceVertex);
  for (int c = 0; c < 3; ++c) EXPECT_EQ(out.image.at(32, 24, c), kVertexColour[size_t(c)]);
  for (int x : {0, kW - 1}) {
    EXPECT_EQ(out.provenance.at(x, 24), kProvenanceBackground);
    for (int c = 0; c < 3; ++c) EXPECT_EQ(out.image.at(x, 24, c), 0.f);
  }
  EXPECT_EQ(out.counts.masked, size_t(kW * kH));
  EXPECT_EQ(out.counts.vertex + out.counts.background, size_t(kW * kH));
  EXPECT_GT(out.counts.vertex, 40u * kH);
  EXPECT_GT(out.counts.background, 10u * kH);
}

TEST(InpaintThroughMesh, WhereNoSurfaceIsSeenTheSkyComesFromThePartner) {
  NeedGl();
  Renderer r(Plane(5));
  const View own = LookingDownZ({0, 0, 0});
  const Image colour = ConstantColour();
  const Image depth = r.RenderDepth(own);  // the partner stands where the image was taken
  Projector p{own, &colour, &depth, nullptr};
  Inpainted out = InpaintThroughMesh(r, own, Pattern(), Image(kW, kH, 1, 8, 255), {p}, 0.005);
  EXPECT_EQ(out.provenance.at(32, 24), 1);
  EXPECT_EQ(out.provenance.at(0, 24), kProvenanceSkyOffset + 1);
  for (int c = 0; c < 3; ++c) {
    EXPECT_EQ(out.image.at(32, 24, c), kPartnerColour[size_t(c)]);
    EXPECT_EQ(out.image.at(0, 24, c), kPartnerColour[size_t(c)]);
  }
  EXPECT_GT(out.counts.sky, 10u * kH);
  EXPECT_GT(out.counts.partners, 40u * kH);
  EXPECT_EQ(out.counts.sky + out.counts.partners + out.counts.vertex + out.counts.background,
            size_t(kW * kH));
}

TEST(InpaintThroughMesh, EmptyMaskCopiesAndSizesAreChecked) {
  NeedGl();
  Renderer r(Plane(50));
  const Image im = Pattern();
  Inpainted out = InpaintThroughMesh(r, LookingDownZ({0, 0, 0}), im, Image(kW, kH, 1, 8), {}, 0);
  EXPECT_EQ(out.image.data, im.data);
  EXPECT_EQ(out.provenance.data, std::vector<float>(size_t(kW * kH), kProvenanceOriginal));
  EXPECT_EQ(out.counts.masked, 0u);
  const Image half(kW / 2, kH / 2, 3, 8);
  try {
    InpaintThroughMesh(r, LookingDownZ({0, 0, 0}), half, Image(kW / 2, kH / 2, 1, 8, 255), {}, 0);
    ADD_FAILURE() << "no error";
  } catch (const Error& e) {
    EXPECT_EQ(std::string(e.what()), "image is 32x24, its camera 64x48");
  }
}

}  // namespace
}  // namespace mvtm
