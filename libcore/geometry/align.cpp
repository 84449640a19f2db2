#include "geometry/align.h"

#include <Eigen/Geometry>
#include <cmath>

#include "base/error.h"

namespace mvtm {

Sim3 AlignUmeyama(const std::vector<Eigen::Vector3d>& src, const std::vector<Eigen::Vector3d>& dst,
                  bool with_scale) {
  if (src.size() != dst.size() || src.size() < 3)
    throw Error("alignment needs at least 3 corresponding points");
  Eigen::Matrix3Xd a(3, src.size()), b(3, dst.size());
  for (size_t i = 0; i < src.size(); ++i) {
    a.col(i) = src[i];
    b.col(i) = dst[i];
  }
  Eigen::Matrix4d m = Eigen::umeyama(a, b, with_scale);
  Sim3 s;
  Eigen::Matrix3d sr = m.topLeftCorner<3, 3>();
  s.scale = std::cbrt(sr.determinant());
  s.R = sr / s.scale;
  s.t = m.topRightCorner<3, 1>();
  return s;
}

double AteRmse(const Sim3& T, const std::vector<Eigen::Vector3d>& src,
               const std::vector<Eigen::Vector3d>& dst) {
  double sum = 0;
  for (size_t i = 0; i < src.size(); ++i) sum += (T * src[i] - dst[i]).squaredNorm();
  return src.empty() ? 0 : std::sqrt(sum / static_cast<double>(src.size()));
}

}  // namespace mvtm
