// mvtm — fusing dense depth maps into one mesh: a multi-view geometric consistency filter, then
// TSDF integration on a sparse volume (OpenVDB) meshed at its zero level set.
//
// Conventions:
//  * A DepthView is one image's depth map with the camera and pose it was computed for: the
//    camera is undistorted and the size of the depth map (for densify output, the image's camera
//    `Scaled` to the map's size); the pose is COLMAP's world-to-camera. Depth is linear
//    camera-space z in float32; +inf, NaN and z <= 0 mean "no depth". Pixel centres follow
//    COLMAP (the top-left pixel's centre is (0.5, 0.5)).
//  * Units are the model's own (SfM and monocular SLAM are not metric). No length is absolute:
//    the voxel size is a fraction of the median camera spacing (the median over views of the
//    distance to the nearest other camera centre) unless given explicitly, the truncation is a
//    number of voxels, the consistency tolerance is relative to depth. Fusion is therefore
//    invariant under similarity transforms of the world (a test holds a scene and its copy
//    scaled by 0.2 and moved to UTM coordinates side by side).
//  * Precision: everything is double until it is expressed relative to the volume's origin (the
//    mean camera centre) in voxel units, which is what OpenVDB's int32 index space and its float
//    values see; mesh vertices are shifted back to world coordinates in double.
//  * Signed distance: projective, along each pixel's ray, in voxels; positive in front of the
//    surface (free space), negative behind it, truncated to ±truncation. Weights are the depth
//    map's confidence (1 when there is none). A mesh cell is emitted only when its 8 corner
//    voxels were all observed with weight > min_weight, so the edge of the observed band never
//    produces spurious surfaces. Faces are counter-clockwise seen from the observing cameras
//    (the free-space side) and vertex normals point that way.
//  * Empty input (no views, or no finite depth anywhere) gives an empty mesh, never an error.
//
// Thread safety: the free functions are reentrant (FilterConsistentDepth uses TBB over views,
// ExtractMesh uses OpenVDB's TBB internally). A TsdfVolume is not: Integrate it from one thread.
#pragma once

#include <Eigen/Core>
#include <cstddef>
#include <limits>
#include <memory>
#include <vector>

#include "camera/camera.h"
#include "geometry/rigid.h"
#include "image/image.h"
#include "scene/mesh.h"

namespace mvtm {

struct DepthView {
  Camera camera;            // undistorted, width × height of `depth`
  Rigid3d world_to_camera;  // the pose of record
  Image depth;              // 1 channel float: linear z; +inf / NaN / <= 0 = none
  Image confidence;         // empty (every weight 1) or 1 channel of depth's size, 0..1
};

// Throws Error("depth view INDEX: ...") when the depth map is not 1 channel of the camera's size,
// the confidence is neither empty nor 1 channel of that size, or the camera is distorted.
void CheckDepthView(const DepthView& view, size_t index);

struct ConsistencyOptions {
  int min_agree = 2;                 // other views that must confirm a pixel, >= 1
  double relative_tolerance = 0.01;  // agreement: |z_j - z| <= tolerance · z, in (0, 1)
  bool witnessed = true;             // fewer than min_agree suffice where fewer views could confirm

  void Check() const;  // throws UsageError naming the option
};

// For each view, its depth map with every pixel set to +inf that fewer than min_agree other
// views confirm: the pixel's 3-D point, reprojected into view j, lands inside j's image in front
// of j, and j's depth there (inverse depth interpolated bilinearly where the 4 neighbours are
// finite, which is exact on planes; else the nearest pixel) is within the tolerance of the
// point's z in j. With `witnessed`, the views needed are at most those that could confirm (j
// has a depth there no nearer than the point, within the tolerance: j saw that far; a view
// that sees nearer is occluded, one with no depth is silent), and at least one: a surface that
// only one other photo sees unoccluded (a facade leaving the frame, a sparse drive) is kept when
// that photo agrees, while one that a second photo sees through still needs both. Throws Error
// when a view's depth/confidence/camera sizes disagree.
std::vector<Image> FilterConsistentDepth(const std::vector<DepthView>& views,
                                         const ConsistencyOptions& options);

struct TsdfOptions {
  double voxel_size = 0;           // model units; 0 = voxel_per_spacing × median camera spacing
  double voxel_per_spacing = 0.1;  // the voxel as a fraction of the median camera spacing, > 0
  double truncation_voxels = 3;    // half-width of the band along each ray, in voxels, >= 1
  double min_weight = 0;           // cells with a corner weight <= this are not meshed, >= 0
  double max_depth_spacings = 0;   // ignore depth beyond this many camera spacings; 0 = all

  void Check() const;  // throws UsageError naming the option
};

// Median over views of the distance from its camera centre to the nearest other one. Throws
// Error when there are fewer than two distinct centres (no scale can be derived).
double MedianCameraSpacing(const std::vector<DepthView>& views);
// Mean camera centre (the volume origin FuseDepthViews uses); zero for no views.
Eigen::Vector3d MeanCameraCentre(const std::vector<DepthView>& views);

// A TSDF and weight volume: voxel (i, j, k) is centred at origin + voxel_size · (i, j, k).
class TsdfVolume {
 public:
  TsdfVolume(const Eigen::Vector3d& origin, double voxel_size, double truncation_voxels);
  ~TsdfVolume();
  TsdfVolume(TsdfVolume&&) noexcept;
  TsdfVolume& operator=(TsdfVolume&&) noexcept;

  // Integrates every finite depth below max_depth (model units): per pixel, only the voxels the
  // ray crosses within ±truncation of the surface point (VDBFusion, Vizzo et al. 2022).
  void Integrate(const DepthView& view, double max_depth = std::numeric_limits<double>::infinity());
  // Triangles of the zero level set (volumeToMesh quads split in two), world coordinates.
  Mesh ExtractMesh(double min_weight = 0) const;

  size_t ActiveVoxels() const;
  double voxel_size() const;
  const Eigen::Vector3d& origin() const;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

struct FusionOptions {
  bool filter = true;  // run FilterConsistentDepth first
  ConsistencyOptions consistency;
  TsdfOptions tsdf;

  void Check() const;
};

// Filter (optional), integrate every view into a volume at the mean camera centre, mesh.
// Empty input or no finite depth: an empty mesh.
Mesh FuseDepthViews(const std::vector<DepthView>& views, const FusionOptions& options);

}  // namespace mvtm
