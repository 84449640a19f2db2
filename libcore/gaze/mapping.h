// mvtm — from a point on the screen to the road and back to the photographs (thesis App. B.1):
// which rendered frame was on screen, the world ray under a screen position, the 3-D point it
// hits on the mesh, and the source photographs that see that point, with the pixel in each.
//
// Conventions:
//  * Frames: frame i is on screen from times[i] until times[i + 1]; the last for the median
//    interval between frames (forever when there is one frame). The frame on screen at t is the
//    last with times[i] <= t.
//  * The render is shown full screen, scaled to it (stretched when the aspect ratios differ): the
//    screen is the render camera scaled to the screen's size (Camera::Scaled), so screen pixel
//    (x, y) (centre of the top-left pixel at (0.5, 0.5)) is the render camera's ray through the
//    same fraction of the image, whatever size the frames were rendered at.
//  * Cameras and poses are COLMAP's (world-to-camera; x right, y down, z forward); the ray's
//    direction has camera z = 1, so a hit's t is the render camera's depth.
//  * Visibility of a point X from a photograph (camera, world-to-camera pose): X is in front
//    (z > 0) and inside the image (0 <= u < width, 0 <= v < height, COLMAP pixels), the photo is on
//    the same side of the surface at X as the viewer (a surface seen from behind is not seen), and
//    X is not occluded:
//      - depth: a baked depth map of the photo (linear z, +inf = no surface) decides where the
//        2×2 pixel centres around (u, v) agree: seen when z <= (1 + tolerance) · the smallest of
//        their depths, hidden when z > (1 + tolerance) · the largest. Otherwise — an occluding
//        edge, or a surface seen at a grazing angle (the road) whose depth changes across a
//        pixel by more than the tolerance — a ray decides, as below. An occluder thinner than
//        the map's pixels may be missed where all four pixels see past it.
//      - ray: no mesh surface between the camera centre and X, stopping short of X by ray_margin
//        of the distance (MeshRaycaster::Occluded decides in float).
// Thread safety: functions are reentrant; MeshRaycaster is used through its const interface.
#pragma once

#include <Eigen/Core>
#include <functional>
#include <optional>
#include <string>
#include <vector>

#include "camera/camera.h"
#include "geometry/rigid.h"
#include "image/image.h"
#include "raycast/mesh_raycaster.h"

namespace mvtm {

class FrameClock {
 public:
  // Throws Error unless times is non-empty, finite and strictly increasing.
  explicit FrameClock(std::vector<double> times);
  // The frame on screen at t, or nullopt when t is before the first or after the last frame.
  std::optional<size_t> FrameAt(double t) const;
  double begin() const { return times_.front(); }
  double end() const { return times_.back() + last_; }  // +inf for a single frame
  size_t size() const { return times_.size(); }

 private:
  std::vector<double> times_;
  double last_ = 0;
};

struct WorldRay {
  Eigen::Vector3d origin, direction;  // direction: camera z = 1 (not unit length)
};

// The world ray through screen position (x, y) when `render` is shown full screen at
// screen_w × screen_h pixels and the camera is at `w2c`.
WorldRay ScreenRay(const Camera& render, const Rigid3d& w2c, double screen_w, double screen_h,
                   double x, double y);

// A photograph that may see a point.
struct SourceView {
  std::string name;
  Camera camera;  // undistorted (PINHOLE / SIMPLE_PINHOLE)
  Rigid3d w2c;    // world-to-camera
};

// The baked depth map of view i (its camera's size), or nullptr (then a ray decides). Called
// only for views X projects into, so a caller may load maps on demand.
using DepthLookup = std::function<const Image*(size_t view)>;

struct SourceHit {
  size_t view = 0;        // index into the views
  double u = 0, v = 0;    // COLMAP pixel of X in the photo
  double depth = 0;       // camera-space z of X
  bool by_depth = false;  // seen by the depth map alone (else a ray decided)
};

struct VisibilityOptions {
  double depth_tolerance = 0.01;  // relative, for depth maps
  double ray_margin = 1e-3;       // relative to the camera-to-point distance, for rays
};

// Every view that sees X (see above), in view order. `normal` is the surface normal at X and
// `viewer` the position X was seen from (the render camera): a view on the other side of the
// surface's plane does not see it.
std::vector<SourceHit> SourcesOf(const Eigen::Vector3d& X, const Eigen::Vector3d& normal,
                                 const Eigen::Vector3d& viewer,
                                 const std::vector<SourceView>& views, const MeshRaycaster& mesh,
                                 const DepthLookup& depth, const VisibilityOptions& options);

}  // namespace mvtm
