// The exact-arc bicycle integrator against circle geometry and straight lines.
#include "drive/bicycle.h"

#include <gtest/gtest.h>

#include <Eigen/Core>
#include <cmath>
#include <cstdio>

namespace mvtm {
namespace {

// (1 − cos x)/x and sin(x)/x in long double: the series below 1e-3, the direct forms above.
long double RefVersinc(long double x) {
  if (std::fabs(x) < 1e-3L) return x / 2 - x * x * x / 24 + x * x * x * x * x / 720;
  return (1 - std::cos(x)) / x;
}
long double RefSinc(long double x) {
  if (std::fabs(x) < 1e-3L) return 1 - x * x / 6 + x * x * x * x / 120;
  return std::sin(x) / x;
}

TEST(Bicycle, SincAndVersincAreExactAtZeroAndAccurateNearIt) {
  EXPECT_EQ(Sinc(0), 1.0);
  EXPECT_EQ(Versinc(0), 0.0);
  for (double x : {1e-300, 1e-12, 1e-8, 9.99e-5, 1e-4, 1.01e-4, 2e-3, 0.5, 3.0, -0.7}) {
    EXPECT_NEAR(Sinc(x), static_cast<double>(RefSinc(x)), 2e-16) << x;
    // 1e-13 relative: the long-double reference loses digits to cancellation just above 1e-3.
    EXPECT_NEAR(Versinc(x) / static_cast<double>(RefVersinc(x)), 1.0, 1e-13) << x;
  }
}

// 10^6 steps of constant steering: every knot on the circle of radius L / tan δ about the
// centre fixed by the start pose (geometry, not the integrator).
TEST(Bicycle, ConstantSteeringStaysOnTheCircleForAMillionSteps) {
  const BicycleParams b;  // L = 2.7, ratio 15
  const double steer = 90, delta = 6 * M_PI / 180, R = b.wheelbase / std::tan(delta);
  const PlanarPose start{100, -50, 0.3};
  const Eigen::Vector2d c(start.x - R * std::sin(start.heading),
                          start.y + R * std::cos(start.heading));
  const size_t n = 1000000;
  std::vector<ControlSample> controls(n + 1);
  for (size_t i = 0; i <= n; ++i) controls[i] = {i * 0.01, steer, 10.0, 0};
  const SteeredPath path(controls, b, start);
  double worst = 0, worst_heading = 0;
  for (size_t i = 0; i <= n; i += 1) {
    const PlanarPose p = path.At(controls[i].time);
    const Eigen::Vector2d r(p.x - c.x(), p.y - c.y());
    worst = std::max(worst, std::abs(r.norm() - R) / R);
    // On a left-turning circle the heading is the radius direction + 90°.
    const double h = std::atan2(r.y(), r.x()) + M_PI / 2;
    worst_heading = std::max(worst_heading, std::abs(std::remainder(h - p.heading, 2 * M_PI)));
  }
  std::printf(
      "1e6 steps (%.0f m, %.0f laps of R = %.4f m): max |r - R|/R = %.3g, heading %.3g rad\n",
      path.length(), path.length() / (2 * M_PI * R), R, worst, worst_heading);
  EXPECT_LE(worst, 1e-9);
  EXPECT_LE(worst_heading, 1e-9);
  // The end pose against the closed form of one arc of the whole length, 10 m/s × 10^4 s (the
  // sum of the steps' lengths telescopes to it; path.length() sums 10^6 rounded terms).
  const double phi = start.heading + 1e5 / R;
  const PlanarPose end = path.At(controls[n].time);
  EXPECT_NEAR(end.x, c.x() + R * std::sin(phi), 1e-9 * R);
  EXPECT_NEAR(end.y, c.y() - R * std::cos(phi), 1e-9 * R);
}

// Deviation from the straight line through `start` along its heading, and the distance along it.
Eigen::Vector2d AlongAndAcross(const PlanarPose& start, const PlanarPose& p) {
  const double c = std::cos(start.heading), s = std::sin(start.heading);
  const double dx = p.x - start.x, dy = p.y - start.y;
  return {dx * c + dy * s, -dx * s + dy * c};
}

TEST(Bicycle, ZeroAndTinySteeringDriveStraight) {
  const BicycleParams b;
  const PlanarPose start{3, 4, 0.3};
  const size_t n = 10000;  // 1 cm steps of 10 m/s for 100 m
  for (double delta : {0.0, 1e-12}) {
    std::vector<ControlSample> controls(n + 1);
    const double steer_deg = delta * 180 / M_PI * b.steering_ratio;
    for (size_t i = 0; i <= n; ++i) controls[i] = {i * 0.001, steer_deg, 10.0, 0};
    const SteeredPath path(controls, b, start);
    const double kappa = std::tan(delta) / b.wheelbase;
    double worst = 0;
    for (size_t i = 0; i <= n; ++i) {
      const Eigen::Vector2d aa = AlongAndAcross(start, path.At(controls[i].time));
      const double s = i * 0.01;
      // The exact arc's offset is κs²/2 (+ O(κ³s⁴)): 0 for δ = 0, ≤ 1.9e-9 m at 100 m for 1e-12.
      worst = std::max(worst, std::abs(aa.y() - kappa * s * s / 2) / std::max(s, 1.0));
      EXPECT_NEAR(aa.x(), s, 1e-12 * std::max(s, 1.0));
    }
    std::printf("delta %g: max |offset - k s^2/2| / s = %.3g over 100 m\n", delta, worst);
    EXPECT_LE(worst, 1e-12);
    const PlanarPose end = path.At(controls[n].time);
    if (delta == 0) {
      EXPECT_EQ(end.heading, start.heading);
    } else {
      EXPECT_NEAR(end.heading - start.heading, kappa * 100, 1e-12);
    }
    // Over the first 5 m, a straight line to 1e-12 of the distance even for δ = 1e-12.
    const Eigen::Vector2d at5 = AlongAndAcross(start, path.At(controls[500].time));
    EXPECT_LE(std::abs(at5.y()) / 5, 1e-12);
  }
}

// Piecewise-constant controls: the end pose does not depend on the output times, and stepping
// arc by arc through any output grid (splitting at the knots) lands on it to rounding.
TEST(Bicycle, EndPoseDoesNotDependOnTheOutputRate) {
  const BicycleParams b;
  std::vector<ControlSample> c;
  for (int i = 0; i <= 20; ++i)
    c.push_back({0.5 * i, 200 * std::sin(0.7 * i) * (i % 3 == 0 ? 0 : 1), 5 + 3 * std::cos(i), 0});
  const PlanarPose start{1e3, 2e3, -2.0};
  const SteeredPath path(c, b, start);
  const PlanarPose end = path.At(c.back().time);
  // The end pose built independently: one exact arc per control interval, from the start.
  PlanarPose chained = start;
  for (size_t i = 0; i + 1 < c.size(); ++i)
    chained = AdvanceArc(chained, c[i].speed * (c[i + 1].time - c[i].time),
                         std::tan(RoadWheelAngle(c[i].steer_deg, b)) / b.wheelbase);
  EXPECT_EQ(end.x, chained.x);
  EXPECT_EQ(end.y, chained.y);
  EXPECT_EQ(end.heading, chained.heading);
  double worst = 0;
  for (double rate : {1.0, 7.0, 10.0, 30.0, 1000.0}) {
    const std::vector<double> times = SampleTimes(c.front().time, c.back().time, rate);
    ASSERT_EQ(times.back(), c.back().time);
    // Chain arcs from output to output (a rate-dependent integration).
    PlanarPose q = start;
    double t = times.front();
    size_t k = 0;
    for (double next : times) {
      while (t < next) {
        while (k + 1 < c.size() && c[k + 1].time <= t) ++k;
        const double stop = std::min(next, k + 1 < c.size() ? c[k + 1].time : next);
        const double kappa = std::tan(RoadWheelAngle(c[k].steer_deg, b)) / b.wheelbase;
        q = AdvanceArc(q, c[k].speed * (stop - t), kappa);
        t = stop;
      }
    }
    worst = std::max({worst, std::hypot(q.x - end.x, q.y - end.y) / path.length(),
                      std::abs(std::remainder(q.heading - end.heading, 2 * M_PI))});
  }
  std::printf("rates 1..1000 Hz: end pose identical; chained arcs within %.3g\n", worst);
  EXPECT_LE(worst, 1e-12);
}

TEST(Bicycle, SteeringIsClampedAndReversingGoesBack) {
  BicycleParams b;
  bool clamped = false;
  EXPECT_NEAR(RoadWheelAngle(150, b, &clamped), 10 * M_PI / 180, 1e-15);
  EXPECT_FALSE(clamped);
  EXPECT_NEAR(RoadWheelAngle(-900, b, &clamped), -35 * M_PI / 180, 1e-15);
  EXPECT_TRUE(clamped);
  const PlanarPose a = AdvanceArc({0, 0, 0}, 5, 0.1);
  const PlanarPose back = AdvanceArc(a, -5, 0.1);
  EXPECT_NEAR(back.x, 0, 1e-14);
  EXPECT_NEAR(back.y, 0, 1e-14);
  EXPECT_NEAR(back.heading, 0, 1e-15);
  // A quarter circle of radius 10 to the left: (10, 10), heading 90°.
  const PlanarPose q = AdvanceArc({0, 0, 0}, 10 * M_PI / 2, 0.1);
  EXPECT_NEAR(q.x, 10, 1e-13);
  EXPECT_NEAR(q.y, 10, 1e-13);
  EXPECT_NEAR(q.heading, M_PI / 2, 1e-15);
}

TEST(Bicycle, SampleTimesEndOnTheLastSample) {
  EXPECT_EQ(SampleTimes(0, 1, 4), (std::vector<double>{0, 0.25, 0.5, 0.75, 1}));
  EXPECT_EQ(SampleTimes(0, 1, 3), (std::vector<double>{0, 1.0 / 3, 2.0 / 3, 1}));
  EXPECT_EQ(SampleTimes(0, 1.1, 2), (std::vector<double>{0, 0.5, 1, 1.1}));
  EXPECT_EQ(SampleTimes(2, 2, 10), (std::vector<double>{2}));
}

}  // namespace
}  // namespace mvtm
