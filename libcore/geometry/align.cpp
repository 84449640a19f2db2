#include "geometry/align.h"

#include <Eigen/Geometry>
#include <Eigen/SVD>
#include <algorithm>
#include <cmath>
#include <limits>

#include "base/error.h"
#include "base/stats.h"

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

namespace {

constexpr double kDegree = 3.14159265358979323846 / 180;

// The rotation R of dst_world = s·R·src_world + t seen by one image: R = R_dstᵀ·R_src.
Eigen::Quaterniond ImageRotation(const Rigid3d& src, const Rigid3d& dst) {
  return NormalizedQuaternion(dst.q.conjugate() * src.q);
}

// Up to `most` indices of 0..n-1, evenly spread.
std::vector<size_t> Spread(size_t n, size_t most) {
  std::vector<size_t> idx;
  for (size_t k = 0; k < std::min(n, most); ++k) idx.push_back(k * n / std::min(n, most));
  return idx;
}

// Median of |C_dst,i - C_dst,j| / |C_src,i - C_src,j| over used pairs (at most 200 images, evenly
// drawn) whose source centres lie over 5 % of the images' extent apart (so frames of a stop, whose
// distances are noise, do not vote); NaN when no pair does.
double MedianScale(const std::vector<Eigen::Vector3d>& cs, const std::vector<Eigen::Vector3d>& cd,
                   const std::vector<bool>& use) {
  std::vector<size_t> used, idx;
  for (size_t i = 0; i < cs.size(); ++i)
    if (use[i]) used.push_back(i);
  for (size_t k : Spread(used.size(), 200)) idx.push_back(used[k]);
  double extent = 0;
  for (size_t i : idx) extent = std::max(extent, (cs[i] - cs[idx[0]]).norm());
  std::vector<double> ratios;
  for (size_t a = 0; a < idx.size(); ++a)
    for (size_t b = a + 1; b < idx.size(); ++b) {
      const double ds = (cs[idx[a]] - cs[idx[b]]).norm();
      if (ds > 0.05 * extent && ds > 0) ratios.push_back((cd[idx[a]] - cd[idx[b]]).norm() / ds);
    }
  return Median(ratios);
}

Eigen::Vector3d Mean(const std::vector<Eigen::Vector3d>& v, const std::vector<bool>& use) {
  Eigen::Vector3d sum = Eigen::Vector3d::Zero();
  double n = 0;
  for (size_t i = 0; i < v.size(); ++i)
    if (use[i]) sum += v[i], n += 1;
  return sum / n;
}

// Kabsch over the used images' centred centres (source scaled by s) and their camera axes in
// world coordinates (weighted by the centres' RMS spread, so roll about a line of centres is
// fixed by the axes).
Eigen::Matrix3d FitRotation(const std::vector<Rigid3d>& src, const std::vector<Rigid3d>& dst,
                            const std::vector<Eigen::Vector3d>& cs,
                            const std::vector<Eigen::Vector3d>& cd, const std::vector<bool>& use,
                            double s) {
  const Eigen::Vector3d ms = Mean(cs, use), md = Mean(cd, use);
  double spread = 0, n = 0;
  for (size_t i = 0; i < cd.size(); ++i)
    if (use[i]) spread += (cd[i] - md).squaredNorm(), n += 1;
  spread = std::sqrt(spread / n);
  const double w = spread > 0 ? spread : 1;
  Eigen::Matrix3d h = Eigen::Matrix3d::Zero();
  for (size_t i = 0; i < src.size(); ++i) {
    if (!use[i]) continue;
    h += (s * (cs[i] - ms)) * (cd[i] - md).transpose();
    // Rows of a world-to-camera rotation are the camera's axes in world coordinates.
    h += w * w * src[i].R().transpose() * dst[i].R();
  }
  Eigen::JacobiSVD<Eigen::Matrix3d> svd(h, Eigen::ComputeFullU | Eigen::ComputeFullV);
  Eigen::Matrix3d d = Eigen::Matrix3d::Identity();
  if ((svd.matrixV() * svd.matrixU().transpose()).determinant() < 0) d(2, 2) = -1;
  return svd.matrixV() * d * svd.matrixU().transpose();
}

}  // namespace

PoseAlignment AlignPoses(const std::vector<Rigid3d>& src, const std::vector<Rigid3d>& dst,
                         bool with_scale) {
  if (src.size() != dst.size() || src.size() < 2)
    throw Error("pose alignment needs at least 2 images seen in both models");
  const size_t n = src.size();
  std::vector<Eigen::Vector3d> cs(n), cd(n);
  std::vector<Eigen::Quaterniond> q(n);
  for (size_t i = 0; i < n; ++i) {
    cs[i] = src[i].Centre();
    cd[i] = dst[i].Centre();
    if (!cs[i].allFinite() || !cd[i].allFinite())
      throw Error("pose alignment: a camera centre is not finite");
    q[i] = ImageRotation(src[i], dst[i]);
  }
  PoseAlignment a;
  a.inlier.assign(n, true);
  // First estimate, least-median: the rotation of the image whose rotation is nearest the others'
  // (medoid), then the scale and translation of the pair of images whose fit leaves the smallest
  // median centre misfit; up to half the images may be wrong.
  std::vector<double> er(n), ec(n);
  size_t medoid = 0;
  double best = std::numeric_limits<double>::infinity();
  const std::vector<size_t> few = Spread(n, 60);
  for (size_t i : few) {
    double sum = 0;
    for (size_t j : few) sum += std::min(RotationAngle(q[i], q[j]), 10 * kDegree);
    if (sum < best) best = sum, medoid = i;
  }
  Sim3 T;
  T.R = q[medoid].toRotationMatrix();
  for (size_t i = 0; i < n; ++i) er[i] = RotationAngle(q[i], q[medoid]);
  best = std::numeric_limits<double>::infinity();
  bool found = false;
  for (size_t ia = 0; ia < few.size(); ++ia)
    for (size_t ib = ia + 1; ib < few.size(); ++ib) {
      const size_t i = few[ia], j = few[ib];
      const double ds = (cs[i] - cs[j]).norm();
      Sim3 h = T;
      if (with_scale) {
        if (!(ds > 0)) continue;
        h.scale = (cd[i] - cd[j]).norm() / ds;
      }
      h.t = 0.5 * (cd[i] + cd[j]) - h.scale * (h.R * (0.5 * (cs[i] + cs[j])));
      for (size_t k = 0; k < n; ++k) ec[k] = (h * cs[k] - cd[k]).norm();
      const double m = Median(ec);
      if (m < best) best = m, T = h, found = true;
    }
  if (!found || !(T.scale > 0 && std::isfinite(T.scale)))
    throw Error("pose alignment: the shared cameras' centres coincide: no scale");
  const Eigen::Vector3d md = Mean(cd, a.inlier);
  double extent = 0;
  for (size_t i = 0; i < n; ++i) extent = std::max(extent, (cd[i] - md).norm());
  for (size_t i = 0; i < n; ++i) ec[i] = (T * cs[i] - cd[i]).norm();
  const double lim_c = 5 * Median(ec) + 1e-9 * extent, lim_r = 5 * Median(er) + 0.01 * kDegree;
  for (size_t i = 0; i < n; ++i) a.inlier[i] = ec[i] <= lim_c && er[i] <= lim_r;
  a.inliers = static_cast<size_t>(std::count(a.inlier.begin(), a.inlier.end(), true));
  if (a.inliers < 2 || 2 * a.inliers <= n)
    throw Error("pose alignment: only " + std::to_string(a.inliers) + " of " + std::to_string(n) +
                " shared images agree on one similarity");
  // Refit on the inliers.
  if (with_scale) T.scale = MedianScale(cs, cd, a.inlier);
  if (!(T.scale > 0 && std::isfinite(T.scale)))
    throw Error("pose alignment: the agreeing cameras' centres coincide: no scale");
  T.R = FitRotation(src, dst, cs, cd, a.inlier, T.scale);
  const Eigen::Vector3d mi = Mean(cd, a.inlier);
  T.t = mi - T.scale * (T.R * Mean(cs, a.inlier));
  a.T = T;
  const Eigen::Quaterniond qr(T.R);
  double sc = 0, sr = 0;
  for (size_t i = 0; i < n; ++i) {
    if (!a.inlier[i]) continue;
    sc += (T * cs[i] - cd[i]).squaredNorm();
    sr += std::pow(RotationAngle(q[i], qr) / kDegree, 2);
    a.extent = std::max(a.extent, (cd[i] - mi).norm());
  }
  a.centre_rms = std::sqrt(sc / static_cast<double>(a.inliers));
  a.rotation_rms_deg = std::sqrt(sr / static_cast<double>(a.inliers));
  return a;
}

double AteRmse(const Sim3& T, const std::vector<Eigen::Vector3d>& src,
               const std::vector<Eigen::Vector3d>& dst) {
  double sum = 0;
  for (size_t i = 0; i < src.size(); ++i) sum += (T * src[i] - dst[i]).squaredNorm();
  return src.empty() ? 0 : std::sqrt(sum / static_cast<double>(src.size()));
}

}  // namespace mvtm
