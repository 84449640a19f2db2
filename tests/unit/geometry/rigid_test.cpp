// Rigid transforms, SLERP and rotation angles, against Eigen's own implementations and closed
// forms (rotation about one axis by a known angle).
#include "geometry/rigid.h"

#include <gtest/gtest.h>

#include <cmath>
#include <random>

#include "base/error.h"
#include "geometry/align.h"

namespace mvtm {
namespace {

Eigen::Quaterniond AxisAngle(double angle, Eigen::Vector3d axis) {
  return Eigen::Quaterniond(Eigen::AngleAxisd(angle, axis.normalized()));
}

Eigen::Quaterniond RandomQ(std::mt19937& g) {
  std::normal_distribution<double> n;
  Eigen::Quaterniond q(n(g), n(g), n(g), n(g));
  return q.normalized();
}

TEST(Rigid, InverseAndCentreMatchMatrices) {
  std::mt19937 g(1);
  for (int i = 0; i < 100; ++i) {
    Rigid3d T(RandomQ(g), Eigen::Vector3d::Random() * 1000);
    Eigen::Matrix4d inv = T.Matrix4().inverse();
    EXPECT_LT((T.Inverse().Matrix4() - inv).cwiseAbs().maxCoeff(), 1e-9);
    // C = -Rᵀt is where the camera sits: T(C) = 0.
    EXPECT_LT((T * T.Centre()).norm(), 1e-9);
    Rigid3d U(RandomQ(g), Eigen::Vector3d::Random());
    EXPECT_LT(((T * U).Matrix4() - T.Matrix4() * U.Matrix4()).cwiseAbs().maxCoeff(), 1e-9);
    // The viewing direction is the third row of R.
    EXPECT_LT((T.ViewDirection() - T.R().row(2).transpose()).norm(), 1e-12);
  }
}

TEST(Rigid, FromMatrixReorthonormalises) {
  Eigen::Matrix<double, 3, 4> m;
  m.leftCols<3>() = AxisAngle(0.3, {1, 2, 3}).toRotationMatrix();
  m.col(3) << 1, 2, 3;
  m(0, 0) += 1e-7;  // printed-and-read-back matrices are not exactly orthonormal
  Rigid3d T = Rigid3d::FromMatrix(m);
  EXPECT_NEAR(T.q.norm(), 1.0, 1e-15);
  EXPECT_LT(RotationAngle(T.q, AxisAngle(0.3, {1, 2, 3})), 1e-7);
}

TEST(Rigid, ZeroQuaternionIsAnError) {
  EXPECT_THROW(NormalizedQuaternion(Eigen::Quaterniond(0, 0, 0, 0)), Error);
  EXPECT_THROW(NormalizedQuaternion(Eigen::Quaterniond(NAN, 0, 0, 0)), Error);
  Eigen::Quaterniond q = NormalizedQuaternion(Eigen::Quaterniond(-2, 0, 0, 0));
  EXPECT_EQ(q.w(), 1.0);  // canonical hemisphere
}

TEST(Slerp, AgreesWithEigen) {
  std::mt19937 g(2);
  for (int i = 0; i < 1000; ++i) {
    Eigen::Quaterniond a = RandomQ(g), b = RandomQ(g);
    double s = std::uniform_real_distribution<double>(0, 1)(g);
    Eigen::Quaterniond ours = Slerp(a, b, s), eigen = a.slerp(s, b);
    EXPECT_LT(RotationAngle(ours, eigen), 1e-12);
    EXPECT_NEAR(ours.norm(), 1.0, 1e-15);
  }
}

TEST(Slerp, ClosedFormAboutOneAxis) {
  // Rotation by θ about an axis: slerp at s is the rotation by s·θ, for θ from 1e-12 to π−1e-9.
  Eigen::Vector3d axis(0.2, -0.5, 0.8);
  for (double theta : {1e-12, 1e-9, 1e-6, 0.1, 1.0, 3.0, M_PI - 1e-9}) {
    for (double s : {0.0, 0.25, 0.5, 0.9, 1.0}) {
      Eigen::Quaterniond got = Slerp(Eigen::Quaterniond::Identity(), AxisAngle(theta, axis), s);
      EXPECT_LE(RotationAngle(got, AxisAngle(s * theta, axis)), 1e-15 + 1e-12 * theta)
          << "theta " << theta << " s " << s;
    }
  }
}

TEST(Slerp, AntipodalRepresentationsTakeTheShortArc) {
  // b and −b are the same rotation: interpolating towards −b must not spin through 360°.
  Eigen::Quaterniond a = AxisAngle(0.2, {0, 0, 1}), b = AxisAngle(0.4, {0, 0, 1});
  Eigen::Quaterniond nb(-b.w(), -b.x(), -b.y(), -b.z());
  for (double s : {0.1, 0.5, 0.9}) {
    EXPECT_LT(RotationAngle(Slerp(a, nb, s), AxisAngle(0.2 + 0.2 * s, {0, 0, 1})), 1e-14);
  }
  // Exactly antipodal (same rotation): every s gives that rotation.
  Eigen::Quaterniond na(-a.w(), -a.x(), -a.y(), -a.z());
  EXPECT_LT(RotationAngle(Slerp(a, na, 0.5), a), 1e-15);
}

TEST(RotationAngle, StableNearZeroAndPi) {
  // acos of the dot product would return 0 for 1e-10 rad; the atan2 form keeps the digits.
  for (double theta : {1e-10, 1e-7, 1e-3, 1.0, M_PI - 1e-7}) {
    double got = RotationAngle(Eigen::Quaterniond::Identity(), AxisAngle(theta, {1, 1, 0}));
    EXPECT_NEAR(got, theta, 1e-15 + theta * 1e-9) << theta;
  }
}

TEST(Align, RecoversAKnownSimilarity) {
  std::mt19937 g(3);
  Sim3 truth;
  truth.scale = 2.5;
  truth.R = AxisAngle(0.7, {1, -1, 2}).toRotationMatrix();
  truth.t << 451000, 5410000, 120;  // UTM-sized offset
  std::vector<Eigen::Vector3d> src, dst;
  for (int i = 0; i < 50; ++i) {
    src.push_back(Eigen::Vector3d::Random() * 10);
    dst.push_back(truth * src.back());
  }
  Sim3 est = AlignUmeyama(src, dst, true);
  EXPECT_NEAR(est.scale, 2.5, 1e-9);
  EXPECT_LT((est.R - truth.R).cwiseAbs().maxCoeff(), 1e-9);
  EXPECT_LT(AteRmse(est, src, dst), 1e-6);
}

}  // namespace
}  // namespace mvtm

namespace mvtm {
namespace {

// A camera level on a road whose up is world +Z, looking along +X: its x axis (right) is world −Y,
// y (down) world −Z, z (forward) world +X; so R's rows are those axes and Up() must be +Z.
TEST(Rigid3d, UpIsTheCamerasMinusYInTheWorld) {
  Eigen::Matrix3d R;
  R.row(0) = Eigen::Vector3d(0, -1, 0).transpose();
  R.row(1) = Eigen::Vector3d(0, 0, -1).transpose();
  R.row(2) = Eigen::Vector3d(1, 0, 0).transpose();
  const Rigid3d level(Eigen::Quaterniond(R), Eigen::Vector3d(5e6, -3, 2));
  EXPECT_LT((level.Up() - Eigen::Vector3d::UnitZ()).norm(), 1e-15);
  // Rolled 90° to the right about its view: up becomes the world's left (+Y).
  const Rigid3d rolled(
      Eigen::Quaterniond(Eigen::AngleAxisd(M_PI / 2, Eigen::Vector3d::UnitZ())) * level.q, level.t);
  EXPECT_LT((rolled.Up() - Eigen::Vector3d::UnitY()).norm(), 1e-12);
  // UpSum: n parallel cameras give n times up (a non-unit quaternion counts as its rotation);
  // opposite ones cancel.
  Rigid3d scaled = level;
  scaled.q.coeffs() *= 3.0;
  EXPECT_LT((UpSum({level, level, scaled}) - 3 * Eigen::Vector3d::UnitZ()).norm(), 1e-12);
  const Rigid3d upside_down(
      Eigen::Quaterniond(Eigen::AngleAxisd(M_PI, Eigen::Vector3d::UnitZ())) * level.q, level.t);
  EXPECT_LT(UpSum({level, upside_down}).norm(), 1e-12);
}

}  // namespace
}  // namespace mvtm
