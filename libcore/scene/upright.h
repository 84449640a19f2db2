// mvtm — a structure-from-motion model made upright and metric from the road it was driven on
// (georef; the video issue's "up and scale").
//
// SfM from photos alone gives a model in an arbitrary frame and unit. A dashcam is mounted at a
// known height above the road (KITTI: 1.65 m), roughly level, and the road under it is the
// dominant surface in the lower middle of every frame, so:
//  * Ground under each camera: the 3-D points that camera or its 3 neighbours on either side (in
//    name order) observe, below its optical axis (depression 2°–60°, lateral within 2 × their
//    depth below the camera), fitted by RANSAC to a
//    plane whose normal lies within 25° of that camera's up axis (−y), then refined by least
//    squares on the inliers. The inlier threshold is relative (5 % of the candidate plane's height
//    below the camera), so the fit is the same in any unit. Cameras with fewer than 12
//    inliers (or under 30 % inliers) have no ground.
//    The camera's height above it is then taken from the lane under the car alone: the median
//    of the heights, along the plane's normal, of the candidates with |x| ≤ y within −20 %/+25 %
//    of the plane's (at least 8; else the plane's own): the wide support gives the normal, but
//    kerbs and pavements beside the road pull the plane's height up.
//  * Up: the inlier-weighted mean of the ground normals (the road's mean normal over the drive
//    estimates gravity; a camera's own axis is tilted by its mounting), else the cameras' mean up
//    when no camera has ground.
//  * Camera height: the median over cameras of the distance from the centre to its ground plane;
//    the scale to metres is camera_height_metres / that.
//  * The upright frame: origin at the first camera's foot point (its centre moved down along up by
//    the camera height), z = up, x = the first camera's viewing direction made level, y = z × x
//    (left), so a drive starts at the origin heading +x on a level road.
// Everything is computed camera-relative in double, so a model at UTM-sized coordinates gives the
// same frame (to rounding) as the same model at the origin: the fit is invariant under
// similarity transforms of the input (same up, same heights relative to the model's unit).
// Thread safety: pure functions of their arguments.
#pragma once

#include <Eigen/Core>
#include <cstddef>

#include "geometry/align.h"
#include "scene/reconstruction.h"

namespace mvtm {

struct GroundFit {
  Eigen::Vector3d up = Eigen::Vector3d::UnitZ();         // unit, world
  Eigen::Vector3d camera_up = Eigen::Vector3d::UnitZ();  // the cameras' mean −y, world
  double camera_height = 0;  // median camera height above its ground, model units (0: none)
  double height_spread = 0;  // median absolute deviation of those heights, model units
  size_t cameras = 0;        // registered images
  size_t cameras_with_ground = 0;
  size_t ground_points = 0;  // inliers summed over cameras
};

// Fits the ground under the registered images of `rec` (ImagesByName() order). Throws Error when
// the model has no registered image.
GroundFit FitGround(const Reconstruction& rec);

// The similarity that maps `rec`'s world into the upright frame above, in metres when
// `camera_height_metres` > 0 (needs fit.camera_height > 0: else Error), else in the model's unit
// (scale 1).
Sim3 UprightTransform(const Reconstruction& rec, const GroundFit& fit, double camera_height_metres);

// Applies `T` (x' = s·R·x + t) to every pose and point of `rec`: the same images seen from the same
// places of the transformed world (world-to-camera rotation R_i·Rᵀ, translation s·t_i − R_i·Rᵀ·t).
void TransformModel(Reconstruction& rec, const Sim3& T);

}  // namespace mvtm
