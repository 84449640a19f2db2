#include "camera/camera.h"

#include <cmath>

#include "base/error.h"
#include "base/text.h"

namespace mvtm {

namespace {
struct ModelInfo {
  CameraModel model;
  const char* name;
  int num_params;
  int num_focal;  // leading parameters that are focal lengths (f, or fx fy)
};
constexpr ModelInfo kModels[] = {
    {CameraModel::kSimplePinhole, "SIMPLE_PINHOLE", 3, 1},
    {CameraModel::kPinhole, "PINHOLE", 4, 2},
    {CameraModel::kSimpleRadial, "SIMPLE_RADIAL", 4, 1},
    {CameraModel::kRadial, "RADIAL", 5, 1},
    {CameraModel::kOpenCV, "OPENCV", 8, 2},
    {CameraModel::kOpenCVFisheye, "OPENCV_FISHEYE", 8, 2},
    {CameraModel::kFullOpenCV, "FULL_OPENCV", 12, 2},
    {CameraModel::kFOV, "FOV", 5, 2},
    {CameraModel::kSimpleRadialFisheye, "SIMPLE_RADIAL_FISHEYE", 4, 1},
    {CameraModel::kRadialFisheye, "RADIAL_FISHEYE", 5, 1},
    {CameraModel::kThinPrismFisheye, "THIN_PRISM_FISHEYE", 12, 2},
};
const ModelInfo& Info(CameraModel m) {
  for (const auto& i : kModels)
    if (i.model == m) return i;
  throw Error("unknown camera model id " + std::to_string(static_cast<int>(m)));
}
}  // namespace

const char* CameraModelName(CameraModel m) { return Info(m).name; }
int CameraModelNumParams(CameraModel m) { return Info(m).num_params; }

CameraModel CameraModelFromName(const std::string& name) {
  for (const auto& i : kModels)
    if (name == i.name) return i.model;
  throw Error("unknown camera model '" + name + "'");
}

CameraModel CameraModelFromId(int id) {
  for (const auto& i : kModels)
    if (static_cast<int>(i.model) == id) return i.model;
  throw Error("unknown camera model id " + std::to_string(id));
}

std::string CameraProblem(const Camera& c) {
  if (c.width == 0 || c.height == 0) return "width and height must be positive";
  if (c.width > kMaxCameraSide || c.height > kMaxCameraSide)
    return "size " + std::to_string(c.width) + "x" + std::to_string(c.height) + " is beyond the " +
           std::to_string(kMaxCameraSide) + " pixels a side mvtm handles";
  const ModelInfo& m = Info(c.model);
  if (static_cast<int>(c.params.size()) != m.num_params)
    return std::string(m.name) + " takes " + std::to_string(m.num_params) + " parameters, got " +
           std::to_string(c.params.size());
  for (double p : c.params)
    if (!std::isfinite(p)) return "parameters must be finite numbers";
  for (int i = 0; i < m.num_focal; ++i)
    if (!(c.params[static_cast<size_t>(i)] > 0))
      return "focal length must be positive, got " + FormatDouble(c.params[static_cast<size_t>(i)]);
  return "";
}

void Camera::RequireUndistorted() const {
  if (!IsUndistorted())
    throw Error("camera " + std::to_string(id) + " is " + CameraModelName(model) +
                ": projective texture mapping needs undistorted images (PINHOLE or "
                "SIMPLE_PINHOLE); run colmap image_undistorter first");
}

double Camera::fx() const {
  RequireUndistorted();
  return params.at(0);
}
double Camera::fy() const {
  RequireUndistorted();
  return model == CameraModel::kSimplePinhole ? params.at(0) : params.at(1);
}
double Camera::cx() const {
  RequireUndistorted();
  return model == CameraModel::kSimplePinhole ? params.at(1) : params.at(2);
}
double Camera::cy() const {
  RequireUndistorted();
  return model == CameraModel::kSimplePinhole ? params.at(2) : params.at(3);
}

Eigen::Matrix3d Camera::K() const {
  Eigen::Matrix3d k = Eigen::Matrix3d::Identity();
  k(0, 0) = fx();
  k(1, 1) = fy();
  k(0, 2) = cx();
  k(1, 2) = cy();
  return k;
}

Eigen::Vector2d Camera::Project(const Eigen::Vector3d& x) const {
  return {fx() * x.x() / x.z() + cx(), fy() * x.y() / x.z() + cy()};
}

Eigen::Vector3d Camera::Unproject(const Eigen::Vector2d& p, double depth) const {
  return {(p.x() - cx()) / fx() * depth, (p.y() - cy()) / fy() * depth, depth};
}

Camera Camera::Scaled(uint64_t w, uint64_t h) const {
  RequireUndistorted();
  Camera c = *this;
  double sx = static_cast<double>(w) / static_cast<double>(width);
  double sy = static_cast<double>(h) / static_cast<double>(height);
  c.width = w;
  c.height = h;
  c.model = CameraModel::kPinhole;
  c.params = {fx() * sx, fy() * sy, cx() * sx, cy() * sy};
  return c;
}

Eigen::Matrix4d Camera::GlProjection(double n, double f) const {
  // Eye coordinates (x right, y up, -z forward) relate to camera coordinates by (x, -y, -z).
  // Pixel u = fx·x/z + cx ↦ NDC x = 2u/W - 1; pixel v = fy·y/z + cy ↦ NDC y = 1 - 2v/H.
  const double W = static_cast<double>(width), H = static_cast<double>(height);
  Eigen::Matrix4d P = Eigen::Matrix4d::Zero();
  P(0, 0) = 2 * fx() / W;
  P(0, 2) = 1 - 2 * cx() / W;
  P(1, 1) = 2 * fy() / H;
  P(1, 2) = 2 * cy() / H - 1;
  P(2, 2) = -(f + n) / (f - n);
  P(2, 3) = -2 * f * n / (f - n);
  P(3, 2) = -1;
  return P;
}

Camera ParseCameraSpec(const std::string& spec) {
  auto tok = SplitBlank(spec);
  if (tok.size() < 3) throw UsageError("--camera: '" + spec + "' needs MODEL W H PARAMS...");
  Camera c;
  try {
    c.model = CameraModelFromName(std::string(tok[0]));
  } catch (const Error& e) {
    throw UsageError(std::string("--camera: ") + e.what());
  }
  const int64_t w = ParseIntArg(tok[1], "--camera"), h = ParseIntArg(tok[2], "--camera");
  if (w <= 0 || h <= 0) throw UsageError("--camera: width and height must be positive");
  c.width = static_cast<uint64_t>(w);
  c.height = static_cast<uint64_t>(h);
  for (size_t i = 3; i < tok.size(); ++i) c.params.push_back(ParseDoubleArg(tok[i], "--camera"));
  std::string problem = CameraProblem(c);
  if (!problem.empty()) throw UsageError("--camera: " + problem);
  return c;
}

}  // namespace mvtm
