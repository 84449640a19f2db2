#include "geo/gps_align.h"

#include <gtest/gtest.h>

#include <GeographicLib/UTMUPS.hpp>
#include <cmath>
#include <random>

#include "base/error.h"

namespace mvtm {
namespace {

// UTM at a zone's central meridian on the equator is (500000, 0) by definition (false easting),
// and the zone of a longitude is floor((lon + 180) / 6) + 1.
TEST(Utm, CentralMeridians) {
  const UtmZone z32 = ZoneOf(0.5, 9.0);
  EXPECT_EQ(z32.zone, 32);
  EXPECT_TRUE(z32.north);
  EXPECT_EQ(z32.Epsg(), 32632);
  EXPECT_EQ(z32.Name(), "32N");
  const Eigen::Vector2d e = ToUtm(z32, 0.0, 9.0);
  EXPECT_NEAR(e.x(), 500000, 1e-6);
  EXPECT_NEAR(e.y(), 0, 1e-6);
  EXPECT_EQ(ZoneOf(-33.9, 18.4).Epsg(), 32734);  // Cape Town: zone 34 south
  EXPECT_EQ(ZoneOf(85.0, 10.0).Epsg(), 32661);   // beyond 84° N: UPS North
  EXPECT_EQ(ZoneOf(-81.0, 10.0).Epsg(), 32761);  // beyond 80° S: UPS South
  // Forced into zone 32, a point just across the border in zone 33 keeps going east (> 500 km).
  EXPECT_GT(ToUtm(z32, 49.0, 12.01).x(), ToUtm(z32, 49.0, 11.99).x());
}

// A curved drive in UTM (zone 32N near Karlsruhe), its upright model = a known similarity of it
// (scale 0.25 model units per metre, turned 40°, moved), 10 Hz frames, 1 Hz fixes.
struct Drive {
  std::vector<Eigen::Vector3d> model;  // camera centres, model units, z up
  std::vector<double> times;           // seconds from the video's start
  std::vector<Eigen::Vector3d> utm;    // true positions (easting, northing, altitude)
  GpsLog log;
};

Drive MakeDrive(double noise, double outlier_share, double log_start, double frame_offset,
                bool stop = false) {
  Drive d;
  const UtmZone z = ZoneOf(49.0, 8.4);
  const double e0 = 455123.4, n0 = 5429876.5, a0 = 115;
  const double th = 40 * M_PI / 180, s = 0.25;
  std::mt19937 rng(7);
  std::normal_distribution<double> n01(0, 1);
  std::uniform_real_distribution<double> u01(0, 1);
  // 12 m/s on an arc of radius 400 m, climbing 2 %; or 15 m/s with a 15 s stop from t = 20 s.
  auto truth = [&](double t) {
    const double along = !stop ? 12 * t : 15 * (std::min(t, 20.0) + std::max(0.0, t - 35));
    const double phi = along / 400;
    return Eigen::Vector3d(400 * std::sin(phi), 400 * (1 - std::cos(phi)), 0.02 * along);
  };
  for (int i = 0; i <= 600; ++i) {
    const double t = 0.1 * i;
    const Eigen::Vector3d p = truth(t);
    d.utm.emplace_back(e0 + p.x(), n0 + p.y(), a0 + p.z());
    d.model.emplace_back(s * (std::cos(th) * p.x() - std::sin(th) * p.y()) + 3,
                         s * (std::sin(th) * p.x() + std::cos(th) * p.y()) - 7, s * p.z() + 0.4);
    d.times.push_back(t + frame_offset);
  }
  for (int k = 0; k <= 60; ++k) {
    const Eigen::Vector3d p = truth(k);
    double e = e0 + p.x() + noise * n01(rng), n = n0 + p.y() + noise * n01(rng);
    if (u01(rng) < outlier_share) e += 60;  // a multipath jump
    GpsFix f;
    f.time = log_start + k;
    GeographicLib::UTMUPS::Reverse(z.zone, z.north, e, n, f.lat, f.lon);
    f.alt = a0 + p.z();
    f.has_alt = true;
    d.log.fixes.push_back(f);
  }
  return d;
}

double HorizontalRms(const Drive& d, const GpsAlignment& a) {
  double ss = 0;
  for (size_t i = 0; i < d.model.size(); ++i) {
    const Eigen::Vector3d p = a.T * d.model[i] + a.origin;
    ss += (p - d.utm[i]).head<2>().squaredNorm();
  }
  return std::sqrt(ss / static_cast<double>(d.model.size()));
}

TEST(GpsAlign, ExactFixesGiveTheSimilarity) {
  const Drive d = MakeDrive(0, 0, 1.3e9, 0);
  const GpsAlignment a = AlignToGps(d.model, d.times, d.log, "log", GpsAlignOptions());
  EXPECT_NEAR(a.T.scale, 4.0, 1e-6);  // metres per model unit = 1 / 0.25
  EXPECT_LT(HorizontalRms(d, a), 1e-3);
  EXPECT_EQ(a.pairs, 61u);
  EXPECT_EQ(a.zone.Epsg(), 32632);
  EXPECT_TRUE(a.has_altitude);
  // Altitude: cameras at the fixes' altitudes.
  const Eigen::Vector3d last = a.T * d.model.back() + a.origin;
  EXPECT_NEAR(last.z(), d.utm.back().z(), 1e-6);
  EXPECT_EQ(a.scale_source, "gps");
}

TEST(GpsAlign, NoisyFixesWithJumps) {
  const Drive d = MakeDrive(3, 0.1, 1.3e9, 0);
  const GpsAlignment a = AlignToGps(d.model, d.times, d.log, "log", GpsAlignOptions());
  // 61 fixes with 3 m noise over a 720 m arc: the scale's standard error is about
  // 3 / sqrt(sum |p - mean|^2) ≈ 3 / sqrt(61 · 210²) ≈ 0.2 %; the jumps are left out.
  EXPECT_NEAR(a.T.scale, 4.0, 4.0 * 0.01);
  EXPECT_LT(HorizontalRms(d, a), 1.5);
  EXPECT_LT(a.inliers, 61u);
  EXPECT_GT(a.inliers, 45u);
  EXPECT_NEAR(a.scale_gps_sigma / a.scale_gps, 0.002, 0.0015);
}

TEST(GpsAlign, CameraHeightScaleIsFusedByItsWeight) {
  const Drive d = MakeDrive(3, 0, 1.3e9, 0);
  GpsAlignOptions o;
  o.height_scale = 4.4;  // 10 % off, claimed good to 2 %: GPS (0.2 %) must dominate
  const GpsAlignment a = AlignToGps(d.model, d.times, d.log, "log", o);
  EXPECT_EQ(a.scale_source, "gps+camera-height");
  const double wg = 1 / std::pow(a.scale_gps_sigma, 2), wh = 1 / std::pow(0.02 * 4.4, 2);
  EXPECT_NEAR(a.T.scale, (wg * a.scale_gps + wh * 4.4) / (wg + wh), 1e-9);
  EXPECT_NEAR(a.T.scale, 4.0, 0.05);
}

TEST(GpsAlign, OffsetSynchronisesAndAbsentOverlapIsAnError) {
  // The video started 2.5 s after the log: frames at t are at log_start + 2.5 + t.
  Drive d = MakeDrive(0, 0, 1.3e9, 0);
  for (double& t : d.times) t -= 2.5;
  GpsAlignOptions o;
  o.offset = 2.5;
  EXPECT_LT(HorizontalRms(d, AlignToGps(d.model, d.times, d.log, "log", o)), 1e-3);
  o.offset = 500;
  try {
    AlignToGps(d.model, d.times, d.log, "track.gpx", o);
    FAIL() << "no error";
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("does not overlap"), std::string::npos) << e.what();
    EXPECT_EQ(e.file(), "track.gpx");
  }
}

TEST(GpsAlign, SearchFindsTheOffset) {
  // The video started 2.37 s after the log; nothing tells the aligner but the fit. At constant
  // speed on an arc a time shift is a rotation (on a straight, a translation) that the similarity
  // absorbs: the offset shows where the speed changes, so this car stops at a red light.
  Drive d = MakeDrive(3, 0, 1.3e9, 0, true);
  for (double& t : d.times) t -= 2.37;
  GpsAlignOptions o;
  o.search = 5;
  const GpsAlignment a = AlignToGps(d.model, d.times, d.log, "log", o);
  EXPECT_NEAR(a.offset, 2.37, 0.1);  // 3 m noise at 15 m/s: a tenth of a second or better
  EXPECT_LT(HorizontalRms(d, a), 1.5);
  o.search = 0;  // as given (0): every moving camera 35 m along the drive from its fix
  EXPECT_GT(HorizontalRms(d, AlignToGps(d.model, d.times, d.log, "log", o)), 5);
}

TEST(GpsAlign, AbsoluteFrameTimes) {
  Drive d = MakeDrive(0, 0, 1.3e9, 1.3e9);  // frames carry the log's own clock
  EXPECT_LT(HorizontalRms(d, AlignToGps(d.model, d.times, d.log, "log", GpsAlignOptions())), 1e-3);
}

}  // namespace
}  // namespace mvtm
