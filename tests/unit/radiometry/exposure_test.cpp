// radiometry/exposure against hand-made truth: images of known gain and offset observing points
// of known radiance (with noise and outliers) give back the gains and offsets in the documented
// gauge; bilinear sampling of the points; exposure.tsv round trip and its errors.
#include "radiometry/exposure.h"

#include <gtest/gtest.h>

#include <cmath>
#include <random>
#include <sstream>

#include "base/error.h"
#include "io/exposure_tsv.h"

namespace mvtm {
namespace {

struct Truth {
  std::vector<double> g, o;
  std::vector<ExposureObservation> obs;
};

// n images, each seeing a window of 120 of the 400 points, exposures spread like KITTI's.
Truth Make(size_t n, bool offsets, double noise, double outlier_share, uint32_t seed) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> gain(0.7, 1.4), off(-12, 12), rad(20, 200), u(0, 1);
  std::normal_distribution<double> nz(0, noise);
  Truth t;
  std::vector<double> L(400);
  for (auto& l : L) l = rad(rng);
  for (size_t i = 0; i < n; ++i) {
    t.g.push_back(gain(rng));
    t.o.push_back(offsets ? off(rng) : 0);
    for (size_t p = (i * 23) % 280; p < (i * 23) % 280 + 120; ++p) {
      double v = t.g[i] * L[p] + t.o[i] + (noise > 0 ? nz(rng) : 0);
      if (u(rng) < outlier_share) v = 255 * u(rng);  // an occluder, a highlight
      t.obs.push_back({i, p, v});
    }
  }
  return t;
}

// The truth in the documented gauge: geometric mean gain 1, mean offset 0.
void Gauge(std::vector<double>& g, std::vector<double>& o) {
  double lg = 0, mo = 0, mg = 0;
  for (size_t i = 0; i < g.size(); ++i) lg += std::log(g[i]), mo += o[i], mg += g[i];
  const double a = std::exp(lg / double(g.size())), c_over_a = mo / mg;
  for (size_t i = 0; i < g.size(); ++i) o[i] -= g[i] * c_over_a, g[i] /= a;
}

TEST(Exposure, GainsAndOffsetsComeBackInTheGauge) {
  Truth t = Make(12, true, 0.5, 0.0, 1);
  ExposureOptions o;
  o.offsets = true;
  const auto e = FitExposure(t.obs, 12, o);
  Gauge(t.g, t.o);
  for (size_t i = 0; i < 12; ++i) {
    ASSERT_TRUE(e[i].fitted);
    EXPECT_NEAR(e[i].gain, t.g[i], 0.01) << i;
    EXPECT_NEAR(e[i].offset, t.o[i], 1.0) << i;  // grey levels, against 0.5 of noise
  }
}

TEST(Exposure, OutliersAreDropped) {
  Truth t = Make(10, true, 0.5, 0.08, 2);  // 8 % of the observations are garbage
  ExposureOptions o;
  o.offsets = true;
  const auto e = FitExposure(t.obs, 10, o);
  Gauge(t.g, t.o);
  for (size_t i = 0; i < 10; ++i) {
    EXPECT_NEAR(e[i].gain, t.g[i], 0.02) << i;
    EXPECT_NEAR(e[i].offset, t.o[i], 2.0) << i;
  }
}

TEST(Exposure, GainsOnlyAndExactData) {
  Truth t = Make(6, false, 0.0, 0.0, 3);
  const auto e = FitExposure(t.obs, 6, ExposureOptions());  // gains only: the default
  Gauge(t.g, t.o);
  for (size_t i = 0; i < 6; ++i) {
    EXPECT_NEAR(e[i].gain, t.g[i], 1e-6) << i;  // alternating least squares: linear convergence
    EXPECT_EQ(e[i].offset, 0.0);
  }
}

TEST(Exposure, ImagesWithTooFewPointsKeepTheIdentity) {
  Truth t = Make(4, true, 0.5, 0.0, 4);
  t.obs.push_back({4, 0, 50});  // image 4 sees a single point
  const auto e = FitExposure(t.obs, 5, ExposureOptions());
  EXPECT_FALSE(e[4].fitted);
  EXPECT_EQ(e[4].gain, 1.0);
  EXPECT_EQ(e[4].offset, 0.0);
  EXPECT_THROW(FitExposure({{7, 0, 1}}, 5, ExposureOptions()), Error);
  EXPECT_TRUE(FitExposure({}, 3, ExposureOptions())[2].gain == 1.0);
}

TEST(Exposure, PointsAreSampledBilinearlyAtTheirPixel) {
  Reconstruction rec;
  rec.cameras[1] = ParseCameraSpec("PINHOLE 8 6 10 10 4 3");
  Point3D p;
  p.id = 9;
  rec.points3D[9] = p;
  ImageRecord im;
  im.id = 1;
  im.camera_id = 1;
  im.name = "a.png";
  Point2D a, outside;
  a.xy = {3.25, 2.0};  // between pixel centres x = 2.5 and 3.5, on the row centre y = 1.5 + 0.5
  a.point3D_id = 9;
  outside.xy = {7.9, 5.9};  // beyond the last pixel centre: skipped
  outside.point3D_id = 9;
  im.points2D = {a, outside};
  rec.images[1] = im;
  Image img(8, 6, 1, 8);
  for (int y = 0; y < 6; ++y)
    for (int x = 0; x < 8; ++x) img.at(x, y) = float(10 * x + y);
  const auto obs = ObservePoints(rec, {&rec.images[1]}, {img});
  ASSERT_EQ(obs.size(), 1u);
  EXPECT_NEAR(obs[0].value, 10 * 2.75 + 1.5, 1e-9);  // x − 0.5 = 2.75, y − 0.5 = 1.5
}

TEST(ExposureTsv, RoundTripAndErrors) {
  std::vector<ExposureRow> rows = {{"A_0000.png", 1.0625, -3.5, 120}, {"B 1.png", 0.9, 0.1, 0}};
  std::ostringstream out;
  WriteExposureTsv(out, rows);
  EXPECT_EQ(out.str(),
            "image\tgain\toffset\tpoints\nA_0000.png\t1.0625\t-3.5\t120\nB "
            "1.png\t0.90000000000000002\t0.10000000000000001\t0\n");
  std::istringstream in(out.str());
  const auto back = ReadExposureTsv(in, "e.tsv");
  ASSERT_EQ(back.size(), 2u);
  EXPECT_EQ(back[1].image, "B 1.png");
  EXPECT_EQ(back[1].gain, 0.9);
  auto fails = [](const std::string& text) {
    std::istringstream s(text);
    try {
      ReadExposureTsv(s, "e.tsv");
    } catch (const Error& e) {
      return std::string(e.what());
    }
    return std::string("no error");
  };
  EXPECT_EQ(fails(""), "e.tsv: empty file: expected the header 'image gain offset points'");
  EXPECT_EQ(fails("image\tgain\toffset\tpoints\na\t0\t0\t1\n"), "e.tsv:2: gain must be > 0");
  EXPECT_EQ(fails("image\tgain\toffset\tpoints\na\t1\t0\n"),
            "e.tsv:2: expected 4 tab-separated fields, found 3");
  EXPECT_EQ(fails("image\tgain\toffset\tpoints\na\t1\t0\t1\na\t1\t0\t1\n"),
            "e.tsv:3: image 'a' appears twice");
}

}  // namespace
}  // namespace mvtm
