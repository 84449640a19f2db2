#include "geometry/rigid.h"

#include <Eigen/SVD>
#include <cmath>

#include "base/error.h"

namespace mvtm {

Rigid3d Rigid3d::operator*(const Rigid3d& b) const { return Rigid3d(q * b.q, q * b.t + t); }

Rigid3d Rigid3d::Inverse() const {
  Eigen::Quaterniond qi = q.conjugate();
  return Rigid3d(qi, -(qi * t));
}

Eigen::Matrix<double, 3, 4> Rigid3d::Matrix3x4() const {
  Eigen::Matrix<double, 3, 4> m;
  m.leftCols<3>() = R();
  m.col(3) = t;
  return m;
}

Eigen::Matrix4d Rigid3d::Matrix4() const {
  Eigen::Matrix4d m = Eigen::Matrix4d::Identity();
  m.topRows<3>() = Matrix3x4();
  return m;
}

Eigen::Vector3d Rigid3d::Centre() const { return -(q.conjugate() * t); }

Eigen::Vector3d Rigid3d::ViewDirection() const { return q.conjugate() * Eigen::Vector3d::UnitZ(); }

Eigen::Vector3d Rigid3d::Up() const { return -(q.conjugate() * Eigen::Vector3d::UnitY()); }

Rigid3d MovedAndTurned(const Rigid3d& w2c, double lateral_left, double yaw_left_deg) {
  Rigid3d c2w = w2c.Inverse();
  const Eigen::Matrix3d R = c2w.R();
  c2w.t -= lateral_left * R.col(0);
  const Eigen::Vector3d up = w2c.Up();
  c2w.q = Eigen::Quaterniond(Eigen::AngleAxisd(yaw_left_deg * M_PI / 180.0, up)) * c2w.q;
  c2w.q.normalize();
  return c2w.Inverse();
}

Eigen::Vector3d UpSum(const std::vector<Rigid3d>& world_to_camera) {
  Eigen::Vector3d sum = Eigen::Vector3d::Zero();
  for (const Rigid3d& p : world_to_camera) sum += Rigid3d(p.q.normalized(), p.t).Up();
  return sum;
}

Rigid3d Rigid3d::FromMatrix(const Eigen::Matrix<double, 3, 4>& m) {
  Eigen::Matrix3d r = m.leftCols<3>();
  Eigen::JacobiSVD<Eigen::Matrix3d> svd(r, Eigen::ComputeFullU | Eigen::ComputeFullV);
  Eigen::Matrix3d d = Eigen::Matrix3d::Identity();
  d(2, 2) = (svd.matrixU() * svd.matrixV().transpose()).determinant() < 0 ? -1 : 1;
  Eigen::Matrix3d rn = svd.matrixU() * d * svd.matrixV().transpose();
  return Rigid3d(NormalizedQuaternion(Eigen::Quaterniond(rn)), m.col(3));
}

Eigen::Quaterniond NormalizedQuaternion(const Eigen::Quaterniond& q) {
  double n = q.norm();
  if (!(n > 0) || !std::isfinite(n)) throw Error("quaternion has zero or non-finite norm");
  Eigen::Quaterniond r(q.coeffs() / n);
  if (r.w() < 0) r.coeffs() = -r.coeffs();
  return r;
}

Eigen::Quaterniond Slerp(const Eigen::Quaterniond& a, const Eigen::Quaterniond& b_in, double s) {
  Eigen::Vector4d va = a.coeffs(), vb = b_in.coeffs();
  if (va.dot(vb) < 0) vb = -vb;
  // phi = angle between the 4-vectors (half the rotation angle): |a-b| = 2 sin(phi/2) and
  // |a+b| = 2 cos(phi/2), so atan2 keeps full relative accuracy for tiny and large angles.
  double phi = std::atan2((va - vb).norm(), (va + vb).norm()) * 2.0;
  Eigen::Vector4d v;
  if (phi < 1e-9) {
    v = (1 - s) * va + s * vb;
  } else {
    double sh = std::sin(phi);
    v = (std::sin((1 - s) * phi) / sh) * va + (std::sin(s * phi) / sh) * vb;
  }
  v.normalize();
  Eigen::Quaterniond r;
  r.coeffs() = v;
  return r;
}

double RotationAngle(const Eigen::Quaterniond& a, const Eigen::Quaterniond& b) {
  Eigen::Vector4d va = a.normalized().coeffs(), vb = b.normalized().coeffs();
  if (va.dot(vb) < 0) vb = -vb;
  return 4.0 * std::atan2((va - vb).norm(), (va + vb).norm());
}

}  // namespace mvtm
