// mvtm — a sparse reconstruction as data: cameras, posed images with their 2-D points, 3-D points.
//
// The data model of a COLMAP sparse model (https://colmap.github.io/format.html), independent of
// any file format (io/colmap_model.h reads and writes it as text or binary).
// Conventions:
//  * Image poses are world-to-camera (QW QX QY QZ TX TY TZ), exactly as COLMAP stores them:
//    camera x right, y down, z forward; the camera centre is C = -R^T t.
//  * Maps are ordered by id, so anything derived from them is deterministic.
//  * Lengths are in the model's own unit (SfM and monocular SLAM are not metric).
// Thread safety: a Reconstruction is a plain value.
#pragma once

#include <Eigen/Core>
#include <cstdint>
#include <map>
#include <string>
#include <vector>

#include "camera/camera.h"
#include "geometry/rigid.h"

namespace mvtm {

inline constexpr uint64_t kInvalidPoint3DId = static_cast<uint64_t>(-1);

struct Point2D {
  Eigen::Vector2d xy = Eigen::Vector2d::Zero();
  uint64_t point3D_id = kInvalidPoint3DId;  // -1 in text
};

struct ImageRecord {
  uint32_t id = 0;
  Rigid3d world_to_camera;  // q as read (normalised only on request), t
  uint32_t camera_id = 0;
  std::string name;
  std::vector<Point2D> points2D;
};

struct TrackElement {
  uint32_t image_id = 0;
  uint32_t point2D_idx = 0;
};

struct Point3D {
  uint64_t id = 0;
  Eigen::Vector3d xyz = Eigen::Vector3d::Zero();
  uint8_t rgb[3] = {0, 0, 0};
  double error = -1;
  std::vector<TrackElement> track;
};

struct Reconstruction {
  std::map<uint32_t, Camera> cameras;
  std::map<uint32_t, ImageRecord> images;
  std::map<uint64_t, Point3D> points3D;

  // Image by name; nullptr when absent.
  const ImageRecord* FindImage(const std::string& name) const;
  // Images sorted by name (the order in which tools process frames).
  std::vector<const ImageRecord*> ImagesByName() const;
  // The camera every render of the model is made with (ptmrender's frames; gazemap maps gaze
  // through the same): the model's first camera (lowest id), which must be undistorted, scaled to
  // width x height when both are given (0: its own size). Throws Error when there is no camera
  // or it is distorted (see Camera::RequireUndistorted).
  Camera RenderCamera(uint64_t width = 0, uint64_t height = 0) const;
};
// The q-quantile (base/stats Percentile, q in 0..1; NaN counts as 0) of the distances from the
// camera centre at which the images see their 3-D points in front of them: every track element
// counts once. 0 when no
// point is seen in front of its camera. Scales with the model (a similarity leaves it in the
// model's own unit).
double ObservedDistanceQuantile(const Reconstruction& rec, double q);
// The scene's far end: the 98th percentile of those distances (0: no points). Renders put their
// sky on a sphere of that radius around the camera (ptmrender --sky-distance).
inline double SceneFarEnd(const Reconstruction& rec) { return ObservedDistanceQuantile(rec, 0.98); }

}  // namespace mvtm
