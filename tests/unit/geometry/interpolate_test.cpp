// Pose interpolation in time: exact keyframe hits, the short arc, drop/clamp, ordering rules.
#include "geometry/interpolate.h"

#include <gtest/gtest.h>

#include "base/error.h"

namespace mvtm {
namespace {

Eigen::Quaterniond Yaw(double a) {
  return Eigen::Quaterniond(Eigen::AngleAxisd(a, Eigen::Vector3d::UnitY()));
}

std::vector<StampedPose> Keys() {
  return {{0.0, Rigid3d(Yaw(0.0), {0, 0, 0}), 1},
          {1.0, Rigid3d(Yaw(0.5), {10, 0, 0}), 2},
          {3.0, Rigid3d(Yaw(0.7), {10, 0, 20}), 3}};
}

TEST(Interpolate, KeyframeTimesReturnTheKeyframeBitForBit) {
  auto k = Keys();
  for (const auto& key : k) {
    auto p = InterpolateCameraToWorld(k, key.time, Outside::kDrop);
    ASSERT_TRUE(p);
    EXPECT_EQ(p->q.coeffs(), key.pose.q.coeffs());
    EXPECT_EQ(p->t, key.pose.t);
  }
}

TEST(Interpolate, LinearCentreAndSlerpRotation) {
  auto k = Keys();
  auto p = InterpolateCameraToWorld(k, 2.0, Outside::kDrop);  // halfway between t=1 and t=3
  ASSERT_TRUE(p);
  EXPECT_LT((p->t - Eigen::Vector3d(10, 0, 10)).norm(), 1e-12);
  EXPECT_LT(RotationAngle(p->q, Yaw(0.6)), 1e-14);
  auto p2 = InterpolateCameraToWorld(k, 0.25, Outside::kDrop);
  EXPECT_LT((p2->t - Eigen::Vector3d(2.5, 0, 0)).norm(), 1e-12);
  EXPECT_LT(RotationAngle(p2->q, Yaw(0.125)), 1e-14);
}

TEST(Interpolate, AntipodalConsecutiveKeyframes) {
  auto k = Keys();
  k[1].pose.q.coeffs() = -k[1].pose.q.coeffs();  // same rotation, other hemisphere
  auto p = InterpolateCameraToWorld(k, 0.5, Outside::kDrop);
  EXPECT_LT(RotationAngle(p->q, Yaw(0.25)), 1e-14);
  auto p2 = InterpolateCameraToWorld(k, 2.0, Outside::kDrop);
  EXPECT_LT(RotationAngle(p2->q, Yaw(0.6)), 1e-14);
}

TEST(Interpolate, IdenticalConsecutiveKeyframes) {
  std::vector<StampedPose> k = {{0.0, Rigid3d(Yaw(0.3), {1, 2, 3}), 1},
                                {1.0, Rigid3d(Yaw(0.3), {1, 2, 3}), 2}};
  for (double t : {0.0, 1e-9, 0.5, 1.0 - 1e-12}) {
    auto p = InterpolateCameraToWorld(k, t, Outside::kDrop);
    ASSERT_TRUE(p);
    EXPECT_LT(RotationAngle(p->q, Yaw(0.3)), 1e-15);
    EXPECT_LT((p->t - Eigen::Vector3d(1, 2, 3)).norm(), 1e-15);
  }
}

TEST(Interpolate, OutsideSpanDropOrClamp) {
  auto k = Keys();
  EXPECT_FALSE(InterpolateCameraToWorld(k, -0.1, Outside::kDrop));
  EXPECT_FALSE(InterpolateCameraToWorld(k, 3.1, Outside::kDrop));
  EXPECT_EQ(InterpolateCameraToWorld(k, -5, Outside::kClamp)->t, k[0].pose.t);
  EXPECT_EQ(InterpolateCameraToWorld(k, 9, Outside::kClamp)->t, k[2].pose.t);
  EXPECT_FALSE(InterpolateCameraToWorld({}, 0.0, Outside::kClamp));
}

TEST(SortKeyframes, SortsCountsAndMergesDuplicates) {
  auto k = Keys();
  std::swap(k[0], k[2]);
  k.push_back(k[1]);  // an exact duplicate (same time, same pose): merged
  EXPECT_EQ(SortKeyframes(k, "kf.txt"), 2u);
  ASSERT_EQ(k.size(), 3u);
  EXPECT_EQ(k[0].time, 0.0);
  EXPECT_EQ(k[2].time, 3.0);
}

TEST(SortKeyframes, ConflictingDuplicateNamesBothLines) {
  auto k = Keys();
  StampedPose d = k[1];
  d.pose.t.x() += 1;
  d.line = 7;
  k.push_back(d);
  try {
    SortKeyframes(k, "kf.txt");
    FAIL();
  } catch (const Error& e) {
    EXPECT_STREQ(e.what(), "kf.txt:7: timestamp 1.000000 repeats line 2 with a different pose");
  }
}

}  // namespace
}  // namespace mvtm
