// Unit tests of libcore/image/ssim.h against hand-derived values. The comparison with
// scikit-image itself is tests/peer/ssim_skimage.py.
#include "image/ssim.h"

#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <random>

namespace mvtm {
namespace {

Image Noise(int w, int h, int c, unsigned seed, int bits = 8) {
  Image img(w, h, c, bits);
  std::mt19937 rng(seed);
  std::uniform_int_distribution<int> d(0, bits == 16 ? 65535 : 255);
  for (float& v : img.data) v = static_cast<float>(d(rng));
  return img;
}

// SSIM of two flat images p and q: the window means are p and q, the (co)variances 0, so
// S = (2pq + C1) / (p² + q² + C1) everywhere.
double FlatSsim(double p, double q, double range, double k1 = 0.01) {
  const double c1 = (k1 * range) * (k1 * range);
  return (2 * p * q + c1) / (p * p + q * q + c1);
}

// The weights scipy.ndimage.gaussian_filter1d puts on a unit impulse (scipy 1.10.1, Debian
// bookworm), printed with repr():
//   x = np.zeros(2*r+1); x[r] = 1; gaussian_filter1d(x, sigma, truncate=3.5, mode='constant')
TEST(GaussianWeights, MatchScipyKernel) {
  SsimOptions o;
  EXPECT_EQ(o.Radius(), 5);  // int(3.5 * 1.5 + 0.5) = int(5.75)
  const std::vector<double> scipy_15 = {
      0.00102838008447911,  0.007598758135239186, 0.036000772128430815, 0.10936068950970002,
      0.2130055377112537,   0.26601172486179436,  0.2130055377112537,   0.10936068950970002,
      0.036000772128430815, 0.007598758135239186, 0.00102838008447911};
  const std::vector<double> w = GaussianWeights(1.5, 5);
  ASSERT_EQ(w.size(), scipy_15.size());
  for (size_t k = 0; k < w.size(); ++k) EXPECT_NEAR(w[k], scipy_15[k], 1e-15) << k;
  o.sigma = 1.0;
  EXPECT_EQ(o.Radius(), 4);  // int(4.0)
  const std::vector<double> scipy_10 = {
      0.00013383062461474175, 0.004431861620031266, 0.053991127420704395,
      0.24197144565660073,    0.39894346935609776,  0.24197144565660073,
      0.053991127420704395,   0.004431861620031266, 0.00013383062461474175};
  const std::vector<double> w1 = GaussianWeights(1.0, 4);
  ASSERT_EQ(w1.size(), scipy_10.size());
  for (size_t k = 0; k < w1.size(); ++k) EXPECT_NEAR(w1[k], scipy_10[k], 1e-15) << k;
}

TEST(Ssim, IdenticalImagesAreExactlyOne) {
  for (int c : {1, 3, 4}) {
    const Image a = Noise(53, 31, c, 1 + c);
    Image map;
    const Similarity s = Compare(a, a, SsimOptions{}, nullptr, &map);
    EXPECT_EQ(s.ssim, 1.0) << c << " channels";
    EXPECT_EQ(s.ncc, 1.0);
    EXPECT_TRUE(std::isinf(s.psnr) && s.psnr > 0);
    for (float v : map.data) ASSERT_EQ(v, 1.0f);
  }
  const Image a16 = Noise(40, 40, 1, 9, 16);
  EXPECT_EQ(Ssim(a16, a16, SsimOptions{}), 1.0);
}

TEST(Ssim, FlatImages) {
  const Image a(30, 20, 1, 8, 100.f), b(30, 20, 1, 8, 140.f);
  const Similarity s = Compare(a, b, SsimOptions{});
  EXPECT_NEAR(s.ssim, FlatSsim(100, 140, 255), 1e-12);
  EXPECT_TRUE(std::isnan(s.ncc));  // zero variance: undefined
  EXPECT_NEAR(s.psnr, 10 * std::log10(255.0 * 255.0 / (40.0 * 40.0)), 1e-12);
  EXPECT_EQ(s.data_range, 255.0);
  EXPECT_EQ(s.ssim_pixels, static_cast<size_t>((30 - 10) * (20 - 10)));
  EXPECT_EQ(s.pixels, 600u);
  // Flat and identical: exactly 1.
  EXPECT_EQ(Ssim(a, a, SsimOptions{}), 1.0);
  // 16-bit: R = 65535.
  const Image c(30, 20, 1, 16, 1000.f), d(30, 20, 1, 16, 30000.f);
  EXPECT_NEAR(Ssim(c, d, SsimOptions{}), FlatSsim(1000, 30000, 65535), 1e-12);
  // Explicit data range and k1.
  SsimOptions o;
  o.data_range = 100;
  o.k1 = 0.05;
  EXPECT_NEAR(Ssim(a, b, o), FlatSsim(100, 140, 100, 0.05), 1e-12);
  // Colour: the channels are averaged.
  Image e(30, 20, 3, 8), f(30, 20, 3, 8);
  for (size_t p = 0; p < e.pixels(); ++p) {
    e.data[p * 3 + 0] = 10, e.data[p * 3 + 1] = 100, e.data[p * 3 + 2] = 200;
    f.data[p * 3 + 0] = 20, f.data[p * 3 + 1] = 100, f.data[p * 3 + 2] = 50;
  }
  EXPECT_NEAR(Ssim(e, f, SsimOptions{}), (FlatSsim(10, 20, 255) + 1.0 + FlatSsim(200, 50, 255)) / 3,
              1e-12);
}

TEST(Ssim, LinearRelationsForNcc) {
  const Image a = Noise(32, 24, 1, 3);
  Image b = a, c = a;
  for (float& v : b.data) v = 2 * v + 3;
  for (float& v : c.data) v = 255 - v;
  b.bits = c.bits = 16;
  Image a16 = a;
  a16.bits = 16;
  EXPECT_NEAR(Compare(a16, b, SsimOptions{}).ncc, 1.0, 1e-14);
  EXPECT_NEAR(Compare(a16, c, SsimOptions{}).ncc, -1.0, 1e-14);
}

TEST(Ssim, PsnrOfOneWrongPixel) {
  Image a(25, 16, 1, 8, 0.f), b = a;
  b.at(7, 9) = 255;  // MSE = 255² / N, so PSNR = 10 log10(N)
  EXPECT_NEAR(Compare(a, b, SsimOptions{}).psnr, 10 * std::log10(25.0 * 16.0), 1e-12);
}

TEST(Ssim, WindowSizeLimits) {
  const Image a = Noise(11, 11, 1, 4), b = Noise(11, 11, 1, 5);
  const Similarity s = Compare(a, b, SsimOptions{});
  EXPECT_EQ(s.ssim_pixels, 1u);
  Image map;
  Ssim(a, b, SsimOptions{}, nullptr, &map);
  EXPECT_NEAR(s.ssim, map.at(5, 5), 1e-6);
  const Image small = Noise(10, 11, 1, 6);
  EXPECT_THROW(Ssim(small, small, SsimOptions{}), Error);
  try {
    Ssim(small, small, SsimOptions{});
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("smaller than the 11x11 SSIM window"), std::string::npos)
        << e.what();
  }
  SsimOptions o;
  o.sigma = 1.0;  // 9x9 window
  EXPECT_NO_THROW(Ssim(Noise(9, 9, 1, 1), Noise(9, 9, 1, 2), o));
  EXPECT_THROW(Ssim(Noise(8, 9, 1, 1), Noise(8, 9, 1, 2), o), Error);
}

TEST(Ssim, MismatchesAndBadOptions) {
  const Image a = Noise(20, 20, 1, 1);
  EXPECT_THROW(Ssim(a, Noise(21, 20, 1, 1), SsimOptions{}), SizeMismatchError);
  EXPECT_THROW(Ssim(a, Noise(20, 20, 3, 1), SsimOptions{}), SizeMismatchError);
  EXPECT_THROW(Ssim(a, Noise(20, 20, 1, 1, 16), SsimOptions{}), Error);
  const Image mask(19, 20, 1, 8, 255.f);
  EXPECT_THROW(Ssim(a, a, SsimOptions{}, &mask), SizeMismatchError);
  SsimOptions o;
  o.sigma = 0;
  EXPECT_THROW(o.Check(), UsageError);
  o = SsimOptions{};
  o.k2 = -1;
  EXPECT_THROW(o.Check(), UsageError);
  o = SsimOptions{};
  o.data_range = std::numeric_limits<double>::quiet_NaN();
  EXPECT_THROW(o.Check(), UsageError);
}

TEST(Ssim, MaskSelectsMapPixels) {
  const Image a = Noise(40, 30, 1, 11), b = Noise(40, 30, 1, 12);
  Image map;
  const Similarity full = Compare(a, b, SsimOptions{}, nullptr, &map);
  // The mean of the map over the cropped region is the SSIM (map stored as float).
  double sum = 0;
  for (int y = 5; y < 25; ++y)
    for (int x = 5; x < 35; ++x) sum += map.at(x, y);
  EXPECT_NEAR(full.ssim, sum / (20 * 30), 1e-6);
  // One pixel inside the cropped region: SSIM = the map there.
  Image one(40, 30, 1, 8, 0.f);
  one.at(17, 12) = 1;
  const Similarity s1 = Compare(a, b, SsimOptions{}, &one);
  EXPECT_EQ(s1.ssim_pixels, 1u);
  EXPECT_EQ(s1.pixels, 1u);
  EXPECT_NEAR(s1.ssim, map.at(17, 12), 1e-6);
  EXPECT_TRUE(std::isnan(s1.ncc));
  EXPECT_NEAR(s1.psnr, 10 * std::log10(255.0 * 255.0 / std::pow(a.at(17, 12) - b.at(17, 12), 2)),
              1e-9);
  // One pixel in the border strip: no SSIM pixel (NaN), PSNR still defined.
  Image edge(40, 30, 1, 8, 0.f);
  edge.at(2, 12) = 255;
  const Similarity se = Compare(a, b, SsimOptions{}, &edge);
  EXPECT_EQ(se.ssim_pixels, 0u);
  EXPECT_TRUE(std::isnan(se.ssim));
  EXPECT_TRUE(std::isfinite(se.psnr));
  // Empty mask: every metric NaN, no error.
  const Image empty(40, 30, 1, 8, 0.f);
  const Similarity s0 = Compare(a, b, SsimOptions{}, &empty);
  EXPECT_EQ(s0.pixels, 0u);
  EXPECT_TRUE(std::isnan(s0.ssim) && std::isnan(s0.ncc) && std::isnan(s0.psnr));
  // A full mask changes nothing.
  const Image all(40, 30, 1, 8, 255.f);
  const Similarity sa = Compare(a, b, SsimOptions{}, &all);
  EXPECT_EQ(sa.ssim, full.ssim);
  EXPECT_EQ(sa.ncc, full.ncc);
  EXPECT_EQ(sa.psnr, full.psnr);
}

TEST(Ssim, ThreadCountDoesNotChangeResults) {
  const Image a = Noise(301, 257, 3, 21), b = Noise(301, 257, 3, 22);
  SsimOptions o;
  o.threads = 1;
  Image map1;
  const Similarity s1 = Compare(a, b, o, nullptr, &map1);
  for (int t : {2, 3, 7}) {
    o.threads = t;
    Image map;
    const Similarity s = Compare(a, b, o, nullptr, &map);
    EXPECT_EQ(s.ssim, s1.ssim) << t;
    EXPECT_EQ(s.ncc, s1.ncc) << t;
    EXPECT_EQ(s.psnr, s1.psnr) << t;
    EXPECT_EQ(map.data, map1.data) << t;
  }
  // Computing the map does not change the mean either.
  EXPECT_EQ(Ssim(a, b, o), s1.ssim);
}

TEST(Ssim, SimdLevelsAgree) {
  // Every kernel variant (those the CPU lacks fall back to the best it has), both radius paths,
  // a width that leaves scalar tail columns, and a row count that leaves a row group tail.
  const Image a = Noise(203, 67, 3, 51), b = Noise(203, 67, 3, 52);
  for (double sigma : {1.5, 1.2}) {
    SsimOptions o;
    o.sigma = sigma;
    Image map_best;
    const Similarity best = Compare(a, b, o, nullptr, &map_best);
    for (SimdLevel level : {SimdLevel::kBaseline, SimdLevel::kAvx2, SimdLevel::kAvx512}) {
      o.simd = level;
      Image map;
      const Similarity s = Compare(a, b, o, nullptr, &map);
      EXPECT_NEAR(s.ssim, best.ssim, 1e-13) << static_cast<int>(level);
      EXPECT_NEAR(s.ncc, best.ncc, 1e-13);
      EXPECT_NEAR(s.psnr, best.psnr, 1e-11);
      for (size_t q = 0; q < map.data.size(); ++q) ASSERT_NEAR(map.data[q], map_best.data[q], 1e-6);
      EXPECT_EQ(Ssim(a, a, o), 1.0);
    }
  }
}

TEST(Ssim, AlphaIsIgnored) {
  Image a = Noise(30, 30, 4, 31), b = a;
  for (size_t p = 0; p < b.pixels(); ++p) b.data[p * 4 + 3] = 0;  // only alpha differs
  EXPECT_EQ(Ssim(a, b, SsimOptions{}), 1.0);
}

TEST(Ssim, GeneralRadius) {
  // sigma 2 (r = 7) takes the generic kernel; symmetric in its arguments like the formula.
  const Image a = Noise(50, 40, 1, 41), b = Noise(50, 40, 1, 42);
  SsimOptions o;
  o.sigma = 2.0;
  EXPECT_EQ(o.Radius(), 7);
  EXPECT_NEAR(Ssim(a, b, o), Ssim(b, a, o), 1e-15);
  const Image c(50, 40, 1, 8, 60.f), d(50, 40, 1, 8, 90.f);
  EXPECT_NEAR(Ssim(c, d, o), FlatSsim(60, 90, 255), 1e-12);
}

}  // namespace
}  // namespace mvtm
