// mvtm — COLMAP camera models.
//
// Conventions:
//  * Models, ids and parameter orders are COLMAP's (src/base/camera_models.h; the table below).
//    All models can be read and written; only the undistorted ones (SIMPLE_PINHOLE, PINHOLE)
//    project — PTM needs undistorted images, and RequireUndistorted() says to run
//    `colmap image_undistorter` otherwise.
//  * Pixel coordinates follow COLMAP: the centre of the top-left pixel is (0.5, 0.5); x right,
//    y down. Camera coordinates: x right, y down, z forward (depth = z, in metres).
//  * GlProjection() returns the OpenGL projection for *OpenGL eye coordinates* (x right, y up,
//    z backward); the axis flip from camera to eye coordinates happens only in libcore/render.
#pragma once

#include <Eigen/Core>
#include <cstdint>
#include <string>
#include <vector>

namespace mvtm {

enum class CameraModel : int {
  kSimplePinhole = 0,
  kPinhole = 1,
  kSimpleRadial = 2,
  kRadial = 3,
  kOpenCV = 4,
  kOpenCVFisheye = 5,
  kFullOpenCV = 6,
  kFOV = 7,
  kSimpleRadialFisheye = 8,
  kRadialFisheye = 9,
  kThinPrismFisheye = 10,
};

// Name ("PINHOLE"), number of parameters, parse by name or id. Throw Error for unknown models.
const char* CameraModelName(CameraModel m);
int CameraModelNumParams(CameraModel m);
CameraModel CameraModelFromName(const std::string& name);
CameraModel CameraModelFromId(int id);

struct Camera {
  uint32_t id = 1;
  CameraModel model = CameraModel::kPinhole;
  uint64_t width = 0, height = 0;
  std::vector<double> params;  // COLMAP order, e.g. PINHOLE: fx fy cx cy

  bool IsUndistorted() const {
    return model == CameraModel::kPinhole || model == CameraModel::kSimplePinhole;
  }
  // Throws Error("camera N is MODEL: ... run colmap image_undistorter") unless undistorted.
  void RequireUndistorted() const;

  double fx() const;
  double fy() const;
  double cx() const;
  double cy() const;
  Eigen::Matrix3d K() const;  // undistorted models only

  // Camera coordinates → pixel (no check that z > 0). Undistorted models only.
  Eigen::Vector2d Project(const Eigen::Vector3d& x_cam) const;
  // Pixel → camera-space point at depth z.
  Eigen::Vector3d Unproject(const Eigen::Vector2d& pixel, double depth) const;

  // Same camera for an image scaled to (w, h): focal lengths and principal point scale with the
  // image, keeping the pixel-centre convention.
  Camera Scaled(uint64_t w, uint64_t h) const;

  // Column-major 4×4 OpenGL projection (eye coordinates: x right, y up, looking down -z) such
  // that NDC x = -1..1 spans pixel columns 0..width and NDC y = +1 is the top row (row 0).
  // Depth maps near..far to NDC -1..1.
  Eigen::Matrix4d GlProjection(double near_plane, double far_plane) const;
};

// Largest width or height accepted for a camera (GL renderbuffers and textures go this far on
// Mesa; a larger value in a model file is a typo, not a camera).
inline constexpr uint64_t kMaxCameraSide = 65536;

// What is wrong with a camera, or "" when it is usable: a size of 0 or beyond kMaxCameraSide, the
// wrong parameter count for its model, a non-finite parameter, a focal length that is not > 0.
// Every reader of cameras (COLMAP text and binary, KITTI calib, ORB-SLAM2 settings, NeRF,
// --camera) applies it, so a bad camera is refused where it enters, naming the file and line.
std::string CameraProblem(const Camera& c);

// Parses "MODEL W H P1 P2 ..." (as on the orb2colmap command line). Throws UsageError.
Camera ParseCameraSpec(const std::string& spec);

}  // namespace mvtm
