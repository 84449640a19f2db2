// mvtm — trajectory alignment and error (for evaluating estimated poses against ground truth).
//
// AlignSim3 is Umeyama's closed-form least-squares similarity (Eigen::umeyama), used as evo does
// for monocular SLAM whose scale is arbitrary. Errors are computed on camera centres.
#pragma once

#include <Eigen/Core>
#include <vector>

namespace mvtm {

struct Sim3 {
  double scale = 1;
  Eigen::Matrix3d R = Eigen::Matrix3d::Identity();
  Eigen::Vector3d t = Eigen::Vector3d::Zero();
  Eigen::Vector3d operator*(const Eigen::Vector3d& x) const { return scale * (R * x) + t; }
};

// Best `dst ≈ s·R·src + t` (with_scale false: s = 1). Needs at least 3 non-collinear points.
Sim3 AlignUmeyama(const std::vector<Eigen::Vector3d>& src, const std::vector<Eigen::Vector3d>& dst,
                  bool with_scale);

// Root mean square of |T(src_i) - dst_i| — the absolute trajectory error (ATE).
double AteRmse(const Sim3& T, const std::vector<Eigen::Vector3d>& src,
               const std::vector<Eigen::Vector3d>& dst);

}  // namespace mvtm
