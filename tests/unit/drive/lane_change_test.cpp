// The lane-change profile against its hand-derived values, and its continuity (C2) checked by
// finite differences — which a profile with an acceleration jump fails.
#include "drive/lane_change.h"

#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>

#include "base/error.h"

namespace mvtm {
namespace {

TEST(LaneChange, HandDerivedValues) {
  const LaneChange lc = LaneChange::Parse("2:4:3.5");
  EXPECT_EQ(lc.start, 2);
  EXPECT_EQ(lc.duration, 4);
  EXPECT_EQ(lc.offset, 3.5);
  EXPECT_EQ(lc.At(1.9).d, 0);
  EXPECT_EQ(lc.At(6.1).d, 3.5);
  EXPECT_NEAR(lc.At(4).d, 1.75, 1e-15);                    // q(1/2) = 1/2
  EXPECT_NEAR(lc.At(4).velocity, 1.875 * 3.5 / 4, 1e-15);  // q'(1/2) = 30/16
  EXPECT_NEAR(lc.At(4).acceleration, 0, 1e-15);
  // q''(σ) peaks at σ = (3 − √3)/6 with 10/√3.
  const double sigma = (3 - std::sqrt(3.0)) / 6;
  EXPECT_NEAR(lc.At(2 + 4 * sigma).acceleration, 10 / std::sqrt(3.0) * 3.5 / 16, 1e-14);
  // q(1/4) = 10/64 − 15/256 + 6/1024 = 0.103515625.
  EXPECT_NEAR(lc.At(3).d, 3.5 * 0.103515625, 1e-15);
}

TEST(LaneChange, VelocityAndAccelerationAreContinuousDerivatives) {
  const LaneChange lc{2, 4, -3.5};
  const double h = 1e-3;
  double worst_v = 0, worst_a = 0, jump_a = 0, jump_v = 0;
  for (double t = 1; t <= 7; t += h) {
    // Central differences of d against the analytic derivatives (error O(h²)).
    const double fd_v = (lc.At(t + h).d - lc.At(t - h).d) / (2 * h);
    const double fd_a = (lc.At(t + h).d - 2 * lc.At(t).d + lc.At(t - h).d) / (h * h);
    worst_v = std::max(worst_v, std::abs(fd_v - lc.At(t).velocity));
    worst_a = std::max(worst_a, std::abs(fd_a - lc.At(t).acceleration));
    jump_v = std::max(jump_v, std::abs(lc.At(t + h).velocity - lc.At(t).velocity));
    jump_a = std::max(jump_a, std::abs(lc.At(t + h).acceleration - lc.At(t).acceleration));
  }
  // The largest step of the acceleration over h is bounded by the peak jerk 60·|D|/T³ times h,
  // also across T0 and T0 + T: no jump. (A cubic smoothstep jumps by 6|D|/T² = 1.3 there.)
  const double jerk = 60 * 3.5 / 64;
  std::printf(
      "lane change: |d' - fd| %.3g, |d'' - fd| %.3g, max step of d' %.3g, of d'' %.3g "
      "(bound %.3g)\n",
      worst_v, worst_a, jump_v, jump_a, jerk * h);
  EXPECT_LE(worst_v, 1e-5);
  EXPECT_LE(worst_a, 1e-3);
  EXPECT_LE(jump_a, jerk * h * 1.0001);
  EXPECT_LE(jump_v, 10 / std::sqrt(3.0) * 3.5 / 16 * h * 1.0001);
  // One-sided limits at the ends.
  for (double t : {2.0, 6.0}) {
    EXPECT_NEAR(lc.At(t - 1e-9).velocity, lc.At(t + 1e-9).velocity, 1e-15);
    EXPECT_NEAR(lc.At(t - 1e-9).acceleration, lc.At(t + 1e-9).acceleration, 1e-6);
  }
}

TEST(LaneChange, BadSpecificationsAreUsageErrors) {
  for (const char* bad : {"1:2", "1:0:3", "1:-1:3", "a:2:3", "1:2:nan", "1:2:3:4", ""})
    EXPECT_THROW(LaneChange::Parse(bad), UsageError) << bad;
}

// On a straight recorded path along x at 10 m/s the moved path is (10 t, d(t)) and points along
// its own velocity (10, d'(t)).
TEST(LaneChange, OnAStraightRecordedPath) {
  std::vector<PlanarSample> path;
  for (int i = 0; i <= 100; ++i) path.push_back({i * 0.1, {i * 1.0, 0, 0}});
  const LaneChange lc{2, 4, 3.5};
  for (double t = 0; t <= 10; t += 0.01) {
    const PlanarPose p = LaneChangePose(path, lc, t);
    const auto v = lc.At(t);
    EXPECT_NEAR(p.x, 10 * t, 1e-12);
    EXPECT_NEAR(p.y, v.d, 1e-12);
    EXPECT_NEAR(p.heading, std::atan2(v.velocity, 10), 1e-15);
  }
  // A recorded path that stands still cannot change lanes.
  std::vector<PlanarSample> still = {{0, {0, 0, 0}}, {10, {0, 0, 0}}};
  EXPECT_THROW(LaneChangePose(still, lc, 3), Error);
  EXPECT_NO_THROW(LaneChangePose(still, lc, 1));
}

}  // namespace
}  // namespace mvtm
