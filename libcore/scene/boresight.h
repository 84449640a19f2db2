// mvtm — the boresight of a camera whose poses are of record (GPS/INS, a SLAM trajectory, a
// dataset's ground truth): the one rotation, shared by every image, between the attitude the
// record gives and the camera's own, fitted to the photos' feature tracks with the record's camera
// centres held fixed.
//
// A record's attitude comes from the vehicle (an inertial unit, a lidar) through a mounting
// calibration; a few tenths of a degree of error there tilt every epipolar geometry the same way,
// and what is triangulated and rendered from those poses is then inconsistent between photos
// (the thesis, §4.3 and Appendix C.2: pose error is a main contributor to PTM error). Bundle
// adjustment with free extrinsics fixes it but lets the trajectory drift (measured on KITTI 01:
// worse renders); one shared rotation has three parameters and cannot drift.
//
// The fit: every camera i becomes R·R_i (world-to-camera rotation; centre C_i unchanged, so
// t_i = -R·R_i·C_i). For a candidate R each point is triangulated again from its observations
// (least squares over the rays, relative to its first camera so that UTM coordinates keep their
// digits) and reprojected; the rotation minimises the Huber-robust sum of squared reprojection
// errors in pixels (Gauss-Newton on the rotation vector with that variable projection, the
// Jacobian by central differences). Observations farther than max_error_px from their point at
// the start, and points seen under less than min_angle_deg of parallax, take no part. A direction
// of rotation the tracks cannot determine (forward motion on a straight road leaves the roll
// about the optical axis nearly free: every epipolar line runs through the epipole whatever the
// roll) stays as recorded: the Gauss-Newton normal matrix at the start is decomposed and the
// directions whose curvature is under `conditioning` times the best-determined one's are frozen.
// Only a rotation that removes at least `min_gain` of the median reprojection error is to be
// applied (BoresightFit::applied): exact poses of record fit a rotation of a few hundredths of a
// degree from the tracks' own systematic error, and turning the cameras by it makes them
// disagree with every other pose of the same record (measured on the fixture: 0.04 degrees,
// 0.5 % of the error, cost 0.02 SSIM off the path against its truth poses).
//
// Conventions: camera axes x right, y down, z forward (rigid.h); the rotation vector's components
// are pitch (about x), yaw (about y) and roll (about z) in radians; undistorted cameras only.
// Thread safety: plain functions over values.
#pragma once

#include <Eigen/Core>
#include <set>
#include <string>
#include <vector>

#include "scene/reconstruction.h"

namespace mvtm {

struct BoresightOptions {
  std::set<std::string> exclude;  // image names whose observations take no part in the fit
  size_t min_track = 3;           // observations of fitted images a point needs
  double min_angle_deg = 1;       // largest angle between a point's rays
  double max_error_px = 4;        // observations farther at the start are outliers
  double huber_px = 1;            // robust scale
  double conditioning = 0.01;     // directions with less relative curvature stay as recorded
  double min_gain = 0.05;         // share of the median reprojection error the fit must remove
};

struct BoresightFit {
  Eigen::Matrix3d R = Eigen::Matrix3d::Identity();     // camera_fitted = R · camera_recorded
  Eigen::Vector3d rotation = Eigen::Vector3d::Zero();  // rotation vector (radians), camera axes
  std::vector<Eigen::Vector3d> frozen;  // unit directions (camera axes) left as recorded
  Eigen::Vector3d curvature = Eigen::Vector3d::Zero();  // normal matrix eigenvalues, ascending
  double sigma_deg = 0;     // standard error of the fitted rotation (largest free direction)
  size_t images = 0;        // fitted images (not excluded, with at least one observation)
  size_t points = 0;        // points that took part
  size_t observations = 0;  // their observations
  size_t outliers = 0;      // observations dropped (> max_error_px at the start)
  double median_before = 0, median_after = 0;  // reprojection error, pixels
  double mean_before = 0, mean_after = 0;
  int iterations = 0;
  // The fit removes at least min_gain of the median reprojection error. When it does not, the
  // rotation is no mount error worth correcting (a fraction of a pixel of systematic bias in
  // the tracks fits a rotation too) and the record's attitude should stay.
  bool applied = false;
};

// Throws Error for a distorted camera, or when fewer than 10 points (or 2 images) take part.
BoresightFit FitBoresight(const Reconstruction& rec, const BoresightOptions& options);

// Every image turned about its centre by R (R·R_i, t = -R·R_i·C_i; quaternions kept in the
// hemisphere w >= 0); every point moved with the first image of its track as if fixed to that
// camera, then refined by Gauss-Newton on its reprojection error over its whole track where its
// rays meet at min_angle_deg or more; its error field becomes its mean reprojection error.
void ApplyBoresight(Reconstruction& rec, const Eigen::Matrix3d& R, double min_angle_deg = 1);

}  // namespace mvtm
