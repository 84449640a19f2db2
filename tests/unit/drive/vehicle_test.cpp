// The live car's pieces against hand-derived values: pedals to speed, the lane position on the
// recorded path, the driving measures, and a path grown sample by sample.
#include "drive/vehicle.h"

#include <gtest/gtest.h>

#include <cmath>

#include "drive/bicycle.h"

namespace mvtm {
namespace {

TEST(Vehicle, FullThrottleFromRestFollowsTheHandIntegratedSpeed) {
  LongitudinalParams lp;  // 3 m/s², rolling 0.15, drag 0.00035 /m
  const Pedals full{0, 1, 0, false};
  // First step from rest: no resistance at rest, so v = 3 · 0.01.
  double v = NextSpeed(0, full, 0.01, lp);
  EXPECT_DOUBLE_EQ(v, 0.03);
  // Second: 0.03 + (3 − 0.15 − 0.00035 · 0.03²) · 0.01.
  EXPECT_DOUBLE_EQ(NextSpeed(v, full, 0.01, lp), 0.03 + (3 - 0.15 - 0.00035 * 0.0009) * 0.01);
  // Terminal speed where 3 = 0.15 + 0.00035 v² (90.2 m/s) is above the cap: the cap holds.
  lp.max_speed = 20;
  v = 0;
  for (int k = 0; k < 20000; ++k) v = NextSpeed(v, full, 0.01, lp);
  EXPECT_EQ(v, 20);
  // Without a cap, the terminal speed.
  lp.max_speed = 1000;
  v = 0;
  for (int k = 0; k < 200000; ++k) v = NextSpeed(v, full, 0.01, lp);
  EXPECT_NEAR(v, std::sqrt((3 - 0.15) / 0.00035), 1e-6);
}

TEST(Vehicle, BrakingStopsAndNeverReverses) {
  const LongitudinalParams lp;
  const Pedals brake{0, 0, 1, false};
  double v = 10, t = 0;
  while (v > 0 && t < 100) {
    v = NextSpeed(v, brake, 0.01, lp);
    t += 0.01;
  }
  EXPECT_EQ(v, 0);
  // 10 m/s at a bit over 8.15 m/s² (brake + rolling + drag): 1.22 s, to a step.
  EXPECT_NEAR(t, 10 / 8.15, 0.02);
  EXPECT_EQ(NextSpeed(0, brake, 0.01, lp), 0);                     // a stopped car stays
  EXPECT_EQ(NextSpeed(0, Pedals{0, 0.5, 1, false}, 0.01, lp), 0);  // brake holds the push
  EXPECT_EQ(NextSpeed(0, Pedals(), 0.01, lp), 0);                  // nothing: nothing
  // Coasting: rolling resistance alone, 0.15 m/s² (plus drag 0.00035 · 1).
  EXPECT_DOUBLE_EQ(NextSpeed(1, Pedals(), 0.1, lp), 1 - (0.15 + 0.00035) * 0.1);
}

TEST(Vehicle, ReverseGearPushesBackwardsToItsCap) {
  const LongitudinalParams lp;  // 3 m/s reversing
  const Pedals back{0, 1, 0, true};
  double v = 0;
  for (int k = 0; k < 1000; ++k) v = NextSpeed(v, back, 0.01, lp);
  EXPECT_EQ(v, -3);
  // Braking while reversing stops at zero.
  for (int k = 0; k < 1000; ++k) v = NextSpeed(v, Pedals{0, 0, 1, true}, 0.01, lp);
  EXPECT_EQ(v, 0);
  // Reverse throttle while rolling forward slows, then reverses.
  v = 1;
  v = NextSpeed(v, back, 0.1, lp);
  EXPECT_DOUBLE_EQ(v, 1 + (-3 - 0.15 - 0.00035) * 0.1);
}

TEST(Vehicle, RecordedPathGivesArcLengthAndSignedOffset) {
  // An L: 10 m along x, then 10 m along y.
  const RecordedPath path({{0, 0}, {10, 0}, {10, 10}});
  EXPECT_DOUBLE_EQ(path.length(), 20);
  PathPoint p = path.Project({4, 1.5});
  EXPECT_DOUBLE_EQ(p.along, 4);
  EXPECT_DOUBLE_EQ(p.offset, 1.5);  // left of travel along +x
  p = path.Project({4, -2});
  EXPECT_DOUBLE_EQ(p.offset, -2);
  p = path.Project({11, 5});  // right of travel along +y
  EXPECT_DOUBLE_EQ(p.along, 15);
  EXPECT_DOUBLE_EQ(p.offset, -1);
  p = path.Project({12, 13});  // past the end: the distance to the end point
  EXPECT_DOUBLE_EQ(p.along, 20);
  EXPECT_NEAR(std::abs(p.offset), std::sqrt(4 + 9), 1e-12);
  EXPECT_EQ(path.Nearest({9, 9}), 2u);
  EXPECT_EQ(path.Nearest({1, -1}), 0u);
  EXPECT_THROW(RecordedPath({{1, 1}, {1, 1}}), std::exception);
}

TEST(Vehicle, DrivingMeasuresAreTimeWeighted) {
  DrivingMeasures m(10);  // limit 10 m/s
  m.Add(1, 8, 0.5);       // 1 s at 8 m/s, 0.5 m left
  m.Add(3, 12, -0.5);     // 3 s at 12 m/s, 0.5 m right
  m.Reset();
  const DrivingSummary s = m.Summary();
  EXPECT_DOUBLE_EQ(s.duration, 4);
  EXPECT_DOUBLE_EQ(s.distance, 44);
  EXPECT_DOUBLE_EQ(s.mean_speed, 11);
  EXPECT_NEAR(s.sd_speed, std::sqrt((64 + 3 * 144) / 4.0 - 121), 1e-12);  // sqrt(3)
  EXPECT_DOUBLE_EQ(s.time_over, 3);
  EXPECT_NEAR(s.rms_over_limit, std::sqrt(3 * 4 / 4.0), 1e-12);
  EXPECT_DOUBLE_EQ(s.mean_offset, -0.25);
  EXPECT_NEAR(s.sdlp, std::sqrt(0.25 - 0.0625), 1e-12);
  EXPECT_DOUBLE_EQ(s.max_offset, 0.5);
  EXPECT_EQ(s.resets, 1u);
}

TEST(Vehicle, APathGrownSampleBySampleIsTheSamePathBitForBit) {
  const BicycleParams b;
  const std::vector<ControlSample> log = {
      {0, 0, 8, 0}, {1, 30, 8, 0}, {2.5, -20, 9, 0}, {4, 0, 7, 0}, {5, 0, 7, 0}};
  const PlanarPose start{3, -2, 0.4};
  const SteeredPath whole(log, b, start);
  SteeredPath grown({log[0]}, b, start);
  for (size_t i = 1; i < log.size(); ++i) grown.Append(log[i]);
  for (double t = 0; t <= 5; t += 0.01) {
    const PlanarPose a = whole.At(t), g = grown.At(t);
    EXPECT_EQ(a.x, g.x);
    EXPECT_EQ(a.y, g.y);
    EXPECT_EQ(a.heading, g.heading);
  }
  EXPECT_EQ(whole.length(), grown.length());
  EXPECT_THROW(grown.Append({5, 0, 1, 0}), std::exception);  // not after the last
  // Past the end the last controls continue: 7 m/s straight on from the end pose.
  const PlanarPose end = whole.At(5), later = whole.Continued(6);
  EXPECT_NEAR(later.x, end.x + 7 * std::cos(end.heading), 1e-12);
  EXPECT_NEAR(later.y, end.y + 7 * std::sin(end.heading), 1e-12);
  EXPECT_EQ(whole.Continued(2).x, whole.At(2).x);
}

}  // namespace
}  // namespace mvtm
