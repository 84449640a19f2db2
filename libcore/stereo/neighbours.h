// mvtm — choosing what a dense-stereo reference image is matched against, and where to sweep.
//
// Conventions: poses are COLMAP world-to-camera; images are indexed in processing order (by
// name, i.e. in time along the drive). Every length is derived from the scene — the median
// spacing of consecutive camera centres, the depths of the sparse points an image sees — so a
// model in any unit (SfM and monocular SLAM are not metric) gets the same choices.
//
// Thread safety: pure functions.
#pragma once

#include <Eigen/Core>
#include <cstddef>
#include <vector>

#include "camera/camera.h"
#include "geometry/rigid.h"
#include "index/pose_index.h"
#include "stereo/plane_sweep.h"

namespace mvtm {

struct NeighbourOptions {
  int count = 4;  // neighbours per image (--neighbours), alternately behind and ahead
  double min_baseline =
      0.25;  // fraction of the median camera spacing below which a neighbour is too close
  double max_angle_deg = 40;  // largest angle between the viewing directions
  double min_coverage =
      0.3;  // share of the reference's sparse points the neighbour must see (when it has any)

  void Check() const;  // throws UsageError naming the option
};

// Median distance between consecutive camera centres (0 when fewer than two images).
double MedianSpacing(const std::vector<Rigid3d>& w2c);

// Neighbours of image `i`: the nearest camera centres of the whole model (libcore/index; other
// drives of the same road included) on both sides along i's optical axis, alternating, the
// nearest of all first; skipping those with too little baseline, too different a viewing
// direction, or (when `ref_points` is not empty) seeing too few of the reference's points.
// Fewer than options.count (even none) when the model offers no more.
// The same for every image of one model: the pose index and the median spacing are built once.
// Keeps references to `w2c` and `cameras`, which must outlive it. Select() is const and
// thread-safe.
class StereoNeighbourFinder {
 public:
  StereoNeighbourFinder(const std::vector<Rigid3d>& w2c, const std::vector<Camera>& cameras,
                        const NeighbourOptions& options);
  std::vector<size_t> Select(size_t i, const std::vector<Eigen::Vector3d>& ref_points) const;

 private:
  const std::vector<Rigid3d>& w2c_;
  const std::vector<Camera>& cameras_;
  NeighbourOptions o_;
  double min_base_;
  PoseIndex index_;
};

std::vector<size_t> SelectStereoNeighbours(const std::vector<Rigid3d>& w2c,
                                           const std::vector<Camera>& cameras, size_t i,
                                           const std::vector<Eigen::Vector3d>& ref_points,
                                           const NeighbourOptions& options);

// The sweep families for a reference view: fronto-parallel over the depths of its points,
// ground-parallel (normal = the drive's "down") and facade-parallel (normal = the drive's
// sideways direction) over its points' offsets along those normals. `down_world` and
// `side_world` are unit world vectors (DriveAxes). No points: no families (nothing to sweep).
std::vector<SweepFamily> SweepFamiliesFor(const Rigid3d& ref_w2c,
                                          const std::vector<Eigen::Vector3d>& ref_points,
                                          const Eigen::Vector3d& down_world,
                                          const Eigen::Vector3d& side_world, int planes);

// The drive's world "down" (mean of the cameras' y axes: dashcams are level) and the sideways
// direction (down × direction of travel), unit vectors.
void DriveAxes(const std::vector<Rigid3d>& w2c, Eigen::Vector3d& down, Eigen::Vector3d& side);

}  // namespace mvtm
