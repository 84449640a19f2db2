#include "camera/camera.h"

#include "base/error.h"
#include "base/text.h"

namespace mvtm {

namespace {
struct ModelInfo {
  CameraModel model;
  const char* name;
  int num_params;
};
constexpr ModelInfo kModels[] = {
    {CameraModel::kSimplePinhole, "SIMPLE_PINHOLE", 3},
    {CameraModel::kPinhole, "PINHOLE", 4},
    {CameraModel::kSimpleRadial, "SIMPLE_RADIAL", 4},
    {CameraModel::kRadial, "RADIAL", 5},
    {CameraModel::kOpenCV, "OPENCV", 8},
    {CameraModel::kOpenCVFisheye, "OPENCV_FISHEYE", 8},
    {CameraModel::kFullOpenCV, "FULL_OPENCV", 12},
    {CameraModel::kFOV, "FOV", 5},
    {CameraModel::kSimpleRadialFisheye, "SIMPLE_RADIAL_FISHEYE", 4},
    {CameraModel::kRadialFisheye, "RADIAL_FISHEYE", 5},
    {CameraModel::kThinPrismFisheye, "THIN_PRISM_FISHEYE", 12},
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
  c.width = static_cast<uint64_t>(ParseIntArg(tok[1], "--camera width"));
  c.height = static_cast<uint64_t>(ParseIntArg(tok[2], "--camera height"));
  if (c.width == 0 || c.height == 0)
    throw UsageError("--camera: width and height must be positive");
  for (size_t i = 3; i < tok.size(); ++i)
    c.params.push_back(ParseDoubleArg(tok[i], "--camera parameter"));
  if (static_cast<int>(c.params.size()) != CameraModelNumParams(c.model))
    throw UsageError("--camera: " + std::string(tok[0]) + " takes " +
                     std::to_string(CameraModelNumParams(c.model)) + " parameters, got " +
                     std::to_string(c.params.size()));
  return c;
}

}  // namespace mvtm
