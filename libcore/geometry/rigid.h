// mvtm — rigid transforms in double precision.
//
// Conventions (stated once for all of mvtm; see DESIGN.md "Conventions"):
//  * A Rigid3d maps points: y = R(q)·x + t, with q a unit Hamilton quaternion (w, x, y, z).
//  * Poses of record are COLMAP's world-to-camera transforms (QW QX QY QZ TX TY TZ); the camera
//    centre is C = -Rᵀt. Camera axes: x right, y down, z forward.
//  * Camera-to-world poses (TUM, ORB-SLAM2, KITTI) are converted on entry with Inverse()
//    (thesis Eq. D.2: R_w2c = R_c2wᵀ, t_w2c = -R_c2wᵀ·t_c2w).
//  * All geometry is double; nothing is stored in float before it is re-centred (libcore/render).
//
// Thread safety: value types, no shared state.
#pragma once

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <vector>

namespace mvtm {

struct Rigid3d {
  Eigen::Quaterniond q = Eigen::Quaterniond::Identity();
  Eigen::Vector3d t = Eigen::Vector3d::Zero();

  Rigid3d() = default;
  Rigid3d(const Eigen::Quaterniond& rotation, const Eigen::Vector3d& translation)
      : q(rotation), t(translation) {}

  Eigen::Matrix3d R() const { return q.toRotationMatrix(); }
  Eigen::Vector3d operator*(const Eigen::Vector3d& x) const { return q * x + t; }
  Rigid3d operator*(const Rigid3d& b) const;  // (this ∘ b)(x) = this(b(x))
  Rigid3d Inverse() const;
  Eigen::Matrix<double, 3, 4> Matrix3x4() const;
  Eigen::Matrix4d Matrix4() const;

  // For a world-to-camera pose: the camera centre in world coordinates, C = -Rᵀt.
  Eigen::Vector3d Centre() const;
  // For a world-to-camera pose: the viewing direction (camera +z) in world coordinates.
  Eigen::Vector3d ViewDirection() const;
  // For a world-to-camera pose: the camera's up axis (camera −y) in world coordinates. mvtm's one
  // definition of "up": a dashcam is level to within a few degrees, so the recorded cameras' up
  // axes, summed (UpSum), give the road's up; every module that needs up derives it here.
  Eigen::Vector3d Up() const;

  // Builds from a 3×4 [R|t] whose R is re-orthonormalised (nearest rotation, via SVD).
  static Rigid3d FromMatrix(const Eigen::Matrix<double, 3, 4>& m);
};

// A world-to-camera pose moved `lateral_left` along the camera's left (−x) and turned
// `yaw_left_deg` degrees to the left about its up axis (−y in the world): a lane change and a
// turn of a level camera (ptmrender --lateral/--yaw, simulate's side screens).
Rigid3d MovedAndTurned(const Rigid3d& w2c, double lateral_left, double yaw_left_deg);

// Σ Up() over world-to-camera poses, unnormalised: its length against the count says how well the
// cameras agree (n when all are parallel, near 0 when they cancel out).
Eigen::Vector3d UpSum(const std::vector<Rigid3d>& world_to_camera);

// Normalises q to unit length and to the canonical hemisphere w >= 0. Throws Error when the norm
// is zero or not finite.
Eigen::Quaterniond NormalizedQuaternion(const Eigen::Quaterniond& q);

// Spherical linear interpolation from a (s = 0) to b (s = 1) along the shorter arc: b is negated
// when a·b < 0 (q and -q are the same rotation). The angle is computed as
// 2·atan2(|a - b|, |a + b|), which stays accurate for nearly equal quaternions where acos of the
// dot product loses half the digits; for an angle below 1e-9 rad it degrades gracefully to a
// normalised linear blend. The result is unit length.
Eigen::Quaterniond Slerp(const Eigen::Quaterniond& a, const Eigen::Quaterniond& b, double s);

// Angle of the relative rotation between a and b in radians (0..π), stable near 0 and π.
double RotationAngle(const Eigen::Quaterniond& a, const Eigen::Quaterniond& b);

}  // namespace mvtm
