// AlignPoses against hand-built models: a straight drive (collinear centres, where centres alone
// leave the roll about the road free) seen in two frames related by a known similarity at UTM
// offsets, with antipodal quaternion signs, noise and wrong poses.
#include "geometry/align.h"

#include <gtest/gtest.h>

#include <cmath>
#include <random>

#include "base/error.h"

namespace mvtm {
namespace {

Eigen::Quaterniond AxisAngle(double angle, Eigen::Vector3d axis) {
  return Eigen::Quaterniond(Eigen::AngleAxisd(angle, axis.normalized()));
}

// A world-to-camera pose of a level camera at `c` heading along +x, turned `yaw` about +z.
Rigid3d Level(const Eigen::Vector3d& c, double yaw) {
  Eigen::Matrix3d r;  // rows: right (-y), down (-z), forward (+x)
  r << 0, -1, 0, 0, 0, -1, 1, 0, 0;
  const Eigen::Matrix3d w2c = r * AxisAngle(-yaw, {0, 0, 1}).toRotationMatrix();
  return Rigid3d(Eigen::Quaterniond(w2c), -(w2c * c));
}

// The pose of the same camera in the world x' = T(x): R' = R·Rtᵀ, C' = T(C), lengths scaled.
Rigid3d Moved(const Rigid3d& w2c, const Sim3& T) {
  const Eigen::Matrix3d r = w2c.R() * T.R.transpose();
  return Rigid3d(Eigen::Quaterniond(r), -(r * (T * w2c.Centre())));
}

Sim3 UtmSimilarity() {
  Sim3 T;
  T.scale = 3.7;
  T.R = AxisAngle(2.9, {0.3, -1, 0.4}).toRotationMatrix();
  T.t << 451234.5, 5410987.25, 312;
  return T;
}

TEST(AlignPoses, StraightRoadAtUtmRecoversTheSimilarity) {
  std::vector<Rigid3d> src, dst;
  const Sim3 truth = UtmSimilarity();
  for (int i = 0; i < 12; ++i) {
    src.push_back(Level({1.3 * i, 0, 1.65}, 0));  // exactly collinear centres
    dst.push_back(Moved(src.back(), truth));
    if (i % 2) dst.back().q.coeffs() *= -1;  // the same rotation, the other sign
  }
  const PoseAlignment a = AlignPoses(src, dst, true);
  EXPECT_EQ(a.inliers, 12u);
  EXPECT_NEAR(a.T.scale, truth.scale, 1e-9);
  EXPECT_LT((a.T.R - truth.R).cwiseAbs().maxCoeff(), 1e-9);
  EXPECT_LT((a.T.t - truth.t).norm(), 1e-6);
  EXPECT_LT(a.centre_rms, 1e-6);
  // Centres alone cannot fix the roll about the road: Umeyama's rotation is wrong here, so the
  // camera axes are what this alignment rests on.
  std::vector<Eigen::Vector3d> cs, cd;
  for (size_t i = 0; i < src.size(); ++i)
    cs.push_back(src[i].Centre()), cd.push_back(dst[i].Centre());
  const Sim3 u = AlignUmeyama(cs, cd, true);
  EXPECT_NEAR(u.scale, truth.scale, 1e-6);
  const Eigen::Vector3d up_true = truth.R * Eigen::Vector3d::UnitZ();
  const Eigen::Vector3d up_u = u.R * Eigen::Vector3d::UnitZ();
  EXPECT_GT(std::acos(std::clamp(up_true.dot(up_u), -1.0, 1.0)), 0.01)
      << "centres alone fixed the roll";
}

TEST(AlignPoses, NoiseAndWrongPoses) {
  std::mt19937 g(7);
  std::normal_distribution<double> n(0, 1);
  const Sim3 truth = UtmSimilarity();
  std::vector<Rigid3d> src, dst;
  for (int i = 0; i < 20; ++i) {
    // A bend: heading turns 20 degrees over the stretch.
    const double yaw = 0.35 * i / 19;
    src.push_back(Level({1.5 * i, 0.02 * i * i, 1.65}, yaw));
    Rigid3d d = Moved(src.back(), truth);
    // 1 mm (times the scale) and 0.02 degree of noise.
    const Eigen::Vector3d c = d.Centre() + truth.scale * 0.001 * Eigen::Vector3d(n(g), n(g), n(g));
    const Eigen::Quaterniond q =
        (d.q * AxisAngle(0.02 * M_PI / 180, {n(g), n(g), n(g)})).normalized();
    d = Rigid3d(q, -(q * c));
    dst.push_back(d);
  }
  // Two wrong poses: one 3 m away, one turned by 10 degrees.
  dst[4] = Rigid3d(dst[4].q, dst[4].t + dst[4].q * Eigen::Vector3d(3 * truth.scale, 0, 0));
  dst[13] = Rigid3d(dst[13].q * AxisAngle(10 * M_PI / 180, {0, 1, 0}), dst[13].t);
  const PoseAlignment a = AlignPoses(src, dst, true);
  EXPECT_FALSE(a.inlier[4]);
  EXPECT_FALSE(a.inlier[13]);
  EXPECT_GE(a.inliers, 16u);
  EXPECT_NEAR(a.T.scale, truth.scale, 0.003 * truth.scale);
  EXPECT_LT(RotationAngle(Eigen::Quaterniond(a.T.R), Eigen::Quaterniond(truth.R)),
            0.05 * M_PI / 180);
  // Each source centre lands within a few millimetres (times the scale) of the truth.
  for (const Rigid3d& s : src)
    EXPECT_LT((a.T * s.Centre() - truth * s.Centre()).norm(), 0.01 * truth.scale);
  EXPECT_LT(a.centre_rms, 0.005 * truth.scale);
  EXPECT_LT(a.rotation_rms_deg, 0.1);
}

TEST(AlignPoses, RigidKeepsTheScaleAndTwoImagesSuffice) {
  Sim3 truth = UtmSimilarity();
  truth.scale = 1;
  std::vector<Rigid3d> src{Level({0, 0, 0}, 0.1), Level({2, 0.1, 0}, 0.12)}, dst;
  for (const Rigid3d& s : src) dst.push_back(Moved(s, truth));
  const PoseAlignment a = AlignPoses(src, dst, false);
  EXPECT_EQ(a.T.scale, 1);
  EXPECT_LT((a.T.R - truth.R).cwiseAbs().maxCoeff(), 1e-9);
  EXPECT_LT((a.T.t - truth.t).norm(), 1e-6);
  EXPECT_THROW(AlignPoses({src[0]}, {dst[0]}, false), Error);
  EXPECT_THROW(AlignPoses({src[0], src[0]}, {dst[0], dst[0]}, true), Error);  // no scale
}

}  // namespace
}  // namespace mvtm
