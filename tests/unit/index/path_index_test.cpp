// PathIndex against hand-derived arc lengths: an L-shaped path, a loop that passes itself, points
// far off the path, UTM-sized coordinates and a single-point path.
#include "index/path_index.h"

#include <gtest/gtest.h>

#include <cmath>

#include "base/error.h"

namespace mvtm {
namespace {

TEST(PathIndex, LShapeGivesTheArcLengthOfTheNearestPoint) {
  // (0,0) → (10,0) → (10,5): 15 units long.
  const PathIndex p({{0, 0, 0}, {10, 0, 0}, {10, 5, 0}}, 0.5);
  EXPECT_DOUBLE_EQ(p.Length(), 15);
  EXPECT_DOUBLE_EQ(p.ArcLength(1), 10);
  auto at = p.Locate({3.3, 2, 0});  // above the first leg: s = 3.3, 2 away
  EXPECT_NEAR(at.s, 3.3, 1e-12);
  EXPECT_NEAR(at.distance, 2, 1e-12);
  at = p.Locate({12, 4, 1});  // beside the second leg: s = 10 + 4, sqrt(4 + 1) away
  EXPECT_NEAR(at.s, 14, 1e-12);
  EXPECT_NEAR(at.distance, std::sqrt(5.0), 1e-12);
  at = p.Locate({-7, 0, 0});  // before the start: the start
  EXPECT_NEAR(at.s, 0, 1e-12);
  EXPECT_NEAR(at.distance, 7, 1e-12);
  at = p.Locate({12, 7, 0});  // beyond the end: the end, sqrt(8) away
  EXPECT_NEAR(at.s, 15, 1e-12);
  EXPECT_NEAR(at.distance, std::sqrt(8.0), 1e-12);
}

TEST(PathIndex, ALoopAnswersWithTheNearerPass) {
  // A square loop of side 10 closing on itself, then on: (0,0) (10,0) (10,10) (0,10) (0,0.5)
  // (10, 0.5): the second pass runs 0.5 above the first.
  const PathIndex p({{0, 0, 0}, {10, 0, 0}, {10, 10, 0}, {0, 10, 0}, {0, 0.5, 0}, {10, 0.5, 0}},
                    0.25);
  auto at = p.Locate({5, 0.1, 0});  // nearer the first pass
  EXPECT_NEAR(at.s, 5, 1e-12);
  at = p.Locate({5, 0.4, 0});  // nearer the second pass: 39.5 + 5
  EXPECT_NEAR(at.s, 44.5, 1e-12);
  EXPECT_NEAR(at.distance, 0.1, 1e-12);
}

TEST(PathIndex, UtmCoordinatesKeepMillimetres) {
  const Eigen::Vector3d o(451000, 5410000, 120);
  const PathIndex p({o, o + Eigen::Vector3d(100, 0, 0), o + Eigen::Vector3d(100, 100, 0)}, 1.0);
  const auto at = p.Locate(o + Eigen::Vector3d(100.5, 37.25, 0.001));
  EXPECT_NEAR(at.s, 137.25, 1e-6);
  EXPECT_NEAR(at.distance, std::hypot(0.5, 0.001), 1e-6);
}

TEST(PathIndex, OnePointAndStops) {
  const PathIndex one({{1, 2, 3}}, 1.0);
  EXPECT_EQ(one.Length(), 0);
  EXPECT_NEAR(one.Locate({1, 2, 7}).distance, 4, 1e-12);
  // A stop (the same point twice) is allowed and adds no length.
  const PathIndex stop({{0, 0, 0}, {0, 0, 0}, {4, 0, 0}}, 1.0);
  EXPECT_DOUBLE_EQ(stop.Length(), 4);
  EXPECT_NEAR(stop.Locate({2, 1, 0}).s, 2, 1e-12);
  EXPECT_THROW(PathIndex({}, 1.0), Error);
  EXPECT_THROW(PathIndex({{0, 0, 0}}, 0.0), Error);
}

}  // namespace
}  // namespace mvtm
