// mvtm — trajectory alignment and error (for evaluating estimated poses against ground truth).
//
// AlignSim3 is Umeyama's closed-form least-squares similarity (Eigen::umeyama), used as evo does
// for monocular SLAM whose scale is arbitrary. Errors are computed on camera centres.
#pragma once

#include <Eigen/Core>
#include <vector>

#include "geometry/rigid.h"

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

// The similarity between two models of the same images, from their world-to-camera poses: T maps
// `src`'s world into `dst`'s (dst_i ≈ src_i ∘ T⁻¹ up to the scale of the camera frame). Used to
// join structure-from-motion models of overlapping stretches of a drive, whose shared cameras lie
// nearly on a line: Umeyama on centres alone leaves the roll about that line free, so the
// rotation also fits the cameras' axes. Robust (least median, fewer than half the images wrong): a
// first estimate takes the per-image rotation nearest the others' (medoid) and the scale and
// translation of the pair of images whose fit leaves the smallest median centre misfit (at most
// 60 images, evenly drawn, make the hypotheses); images whose centre or rotation misfits more
// than 5 times the median misfit (plus 1e-9 of the centres' extent and 0.01 degrees, so
// noise-free inputs keep every image) are outliers; the inliers then give the rotation by Kabsch
// over their centred centres and their axes (weighted by the centres' RMS spread), the scale as
// the median distance ratio and the translation as the mean. with_scale false: scale 1. Throws
// Error under 2 images, for a centre not finite, when the centres coincide and a scale is asked
// for, or unless over half the images agree.
struct PoseAlignment {
  Sim3 T;
  std::vector<bool> inlier;  // per input pair
  size_t inliers = 0;
  double centre_rms = 0;        // |T(C_src) - C_dst| over inliers, dst units
  double rotation_rms_deg = 0;  // per-image rotation misfit over inliers
  double extent = 0;            // largest distance of an inlier's dst centre from their mean
};
PoseAlignment AlignPoses(const std::vector<Rigid3d>& src_w2c, const std::vector<Rigid3d>& dst_w2c,
                         bool with_scale);

// Root mean square of |T(src_i) - dst_i| — the absolute trajectory error (ATE).
double AteRmse(const Sim3& T, const std::vector<Eigen::Vector3d>& src,
               const std::vector<Eigen::Vector3d>& dst);

}  // namespace mvtm
