// mvtm — COLMAP sparse models: cameras, images, points3D in text (.txt) and binary (.bin).
//
// Format: https://colmap.github.io/format.html (text) and COLMAP's
// src/base/reconstruction.cc (binary: little-endian, uint64 counts, camera model ids).
// Conventions:
//  * Image poses are world-to-camera (QW QX QY QZ TX TY TZ), exactly as COLMAP stores them.
//  * Maps are ordered by id, so writing is deterministic; the text writer reproduces COLMAP
//    3.8's own text output byte for byte (header comments, %.17g numbers), so
//    `colmap model_converter` of our files gives back identical text.
//  * Readers check ids (duplicate ids, images naming a camera that does not exist, tracks naming
//    images or 2-D points that do not exist) and report "FILE:LINE: what"; binary readers report
//    the byte offset instead of a line.
//
// Thread safety: functions are reentrant; a Reconstruction is a plain value.
#pragma once

#include <cstdint>
#include <map>
#include <string>
#include <vector>

#include <Eigen/Core>

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
};

// Reads DIR/{cameras,images,points3D}.{txt,bin}: binary when all three .bin exist, else text.
// Throws Error.
Reconstruction ReadColmapModel(const std::string& dir);
Reconstruction ReadColmapText(const std::string& dir);
Reconstruction ReadColmapBinary(const std::string& dir);
// Writes the three files atomically (each to a temporary name, then renamed).
void WriteColmapText(const Reconstruction& r, const std::string& dir);
void WriteColmapBinary(const Reconstruction& r, const std::string& dir);
// True when DIR holds a model (text or binary).
bool HasColmapModel(const std::string& dir);

}  // namespace mvtm
