// The upright, metric frame of an SfM-like model (scene/upright.h) against a synthetic drive
// whose road plane, up axis and camera height are known by construction: a dashcam 1.65 m above a
// level road, pitched down 4° and rolled 1° on its mount, beside walls and parked cars, seen
// through a pinhole; the same model moved by a similarity (scale 0.37, any rotation, UTM-sized
// offset) must come back to the same metric frame.
#include "scene/upright.h"

#include <gtest/gtest.h>

#include <Eigen/Geometry>
#include <cmath>
#include <random>

#include "base/error.h"

namespace mvtm {
namespace {

constexpr double kPi = 3.14159265358979323846;
constexpr double kHeight = 1.65;
constexpr double kFocal = 718.856, kCx = 607.19, kCy = 185.22;
constexpr int kWidth = 1241, kHeightPx = 376;

double PathY(double x) { return 0.002 * x * x; }

// The camera-to-world rotation of a level camera heading along `forward` (z up world), then
// pitched down and rolled on its mount.
Eigen::Matrix3d CameraToWorld(const Eigen::Vector3d& forward, double pitch, double roll) {
  const Eigen::Vector3d up = Eigen::Vector3d::UnitZ();
  const Eigen::Vector3d f = forward.normalized();
  const Eigen::Vector3d right = f.cross(up).normalized();
  const Eigen::Vector3d down = f.cross(right);
  Eigen::Matrix3d c2w;
  c2w << right, down, f;
  // Mount: pitch about the camera's x axis (forward dips), roll about its z axis.
  const Eigen::Matrix3d mount = (Eigen::AngleAxisd(-pitch, Eigen::Vector3d::UnitX()) *
                                 Eigen::AngleAxisd(roll, Eigen::Vector3d::UnitZ()))
                                    .toRotationMatrix();
  return c2w * mount;
}

struct Drive {
  Reconstruction rec;
  std::vector<Eigen::Vector3d> centres;  // true, metric, z up
};

// 51 cameras a metre apart along a gentle curve; road points (1 cm noise), walls 7 m either side
// and parked cars; every point a camera sees within 60 m is observed by it.
Drive MakeDrive(bool with_road) {
  std::mt19937 g(7);
  std::uniform_real_distribution<double> u(0, 1);
  std::normal_distribution<double> noise(0, 0.01);
  Drive d;
  Camera cam;
  cam.id = 1;
  cam.model = CameraModel::kPinhole;
  cam.width = kWidth;
  cam.height = kHeightPx;
  cam.params = {kFocal, kFocal, kCx, kCy};
  d.rec.cameras[1] = cam;
  uint64_t pid = 1;
  auto add = [&](const Eigen::Vector3d& x) {
    Point3D p;
    p.id = pid++;
    p.xyz = x;
    d.rec.points3D[p.id] = p;
  };
  if (with_road)
    for (int i = 0; i < 4000; ++i) {
      const double x = -10 + 80 * u(g);
      add({x, PathY(x) + (u(g) - 0.5) * 10, noise(g)});
    }
  for (int i = 0; i < 3000; ++i) {
    const double x = -10 + 80 * u(g);
    add({x, PathY(x) + (u(g) < 0.5 ? -7 : 7), 8 * u(g)});
  }
  for (int car = 0; car < 6; ++car) {  // parked cars on the right, 1.8 m wide, 1.5 m tall
    const double x0 = 8 + 9 * car;
    for (int i = 0; i < 60; ++i) {
      const double x = x0 + 4 * u(g);
      add({x, PathY(x) - 4 + 1.8 * u(g), 0.3 + 1.2 * u(g)});
    }
  }
  for (int i = 0; i <= 50; ++i) {
    const double x = i;
    const Eigen::Vector3d c(x, PathY(x), kHeight);
    const Eigen::Matrix3d c2w = CameraToWorld({1, 0.004 * x, 0}, 4 * kPi / 180, 1 * kPi / 180);
    ImageRecord im;
    im.id = static_cast<uint32_t>(i + 1);
    im.camera_id = 1;
    char name[32];
    std::snprintf(name, sizeof name, "%06d.png", i);
    im.name = name;
    const Eigen::Matrix3d R = c2w.transpose();
    im.world_to_camera = Rigid3d(Eigen::Quaterniond(R), -R * c);
    for (auto& [id, p] : d.rec.points3D) {
      const Eigen::Vector3d pc = im.world_to_camera * p.xyz;
      if (pc.z() < 1 || pc.z() > 60) continue;
      const double px = kFocal * pc.x() / pc.z() + kCx, py = kFocal * pc.y() / pc.z() + kCy;
      if (px < 0 || py < 0 || px >= kWidth || py >= kHeightPx) continue;
      Point2D o;
      o.xy = {px, py};
      o.point3D_id = id;
      p.track.push_back({im.id, static_cast<uint32_t>(im.points2D.size())});
      im.points2D.push_back(o);
    }
    d.centres.push_back(c);
    d.rec.images[im.id] = std::move(im);
  }
  return d;
}

Sim3 Moved() {
  Sim3 S;
  S.scale = 0.37;
  S.R = Eigen::AngleAxisd(1.1, Eigen::Vector3d(0.3, -0.5, 0.8).normalized()).toRotationMatrix();
  S.t = {452311.25, 5411203.5, 127.0};
  return S;
}

Eigen::Vector3d Centre(const ImageRecord& im) {
  return -(im.world_to_camera.q.toRotationMatrix().transpose() * im.world_to_camera.t);
}

double Degrees(const Eigen::Vector3d& a, const Eigen::Vector3d& b) {
  return std::acos(std::clamp(a.normalized().dot(b.normalized()), -1.0, 1.0)) * 180 / kPi;
}

TEST(Upright, TransformModelKeepsEveryObservationWhereItWas) {
  const Drive d = MakeDrive(true);
  Reconstruction moved = d.rec;
  TransformModel(moved, Moved());
  double worst = 0;
  for (const auto& [id, im] : moved.images)
    for (const Point2D& o : im.points2D) {
      const Eigen::Vector3d pc = im.world_to_camera * moved.points3D.at(o.point3D_id).xyz;
      const Eigen::Vector2d px(kFocal * pc.x() / pc.z() + kCx, kFocal * pc.y() / pc.z() + kCy);
      worst = std::max(worst, (px - o.xy).norm());
    }
  EXPECT_LT(worst, 1e-5) << "pixels (the moved model sits 5.4e6 from its origin)";
}

TEST(Upright, FindsTheRoadsUpAndTheCameraHeightInAMovedAndScaledModel) {
  const Drive d = MakeDrive(true);
  Reconstruction moved = d.rec;
  const Sim3 S = Moved();
  TransformModel(moved, S);
  const GroundFit fit = FitGround(moved);
  EXPECT_EQ(fit.cameras, 51u);
  EXPECT_GE(fit.cameras_with_ground, 45u);
  const Eigen::Vector3d true_up = S.R * Eigen::Vector3d::UnitZ();
  EXPECT_LT(Degrees(fit.up, true_up), 0.3);
  // The cameras' own up is off by the mount's pitch and roll: the road, not the camera, gives up.
  EXPECT_GT(Degrees(fit.camera_up, true_up), 3.5);
  EXPECT_NEAR(fit.camera_height / (S.scale * kHeight), 1.0, 0.01);
}

TEST(Upright, GivesTheMetricDriveBackFromTheCameraHeight) {
  const Drive d = MakeDrive(true);
  Reconstruction moved = d.rec;
  TransformModel(moved, Moved());
  const GroundFit fit = FitGround(moved);
  const Sim3 T = UprightTransform(moved, fit, kHeight);
  TransformModel(moved, T);
  // The truth is already upright with its first camera's foot at the origin heading +x (the
  // camera's forward made level), so the output's centres are the truth's.
  double worst = 0;
  for (size_t i = 0; i < d.centres.size(); ++i) {
    const auto* im = moved.ImagesByName()[i];
    worst = std::max(worst, (Centre(*im) - d.centres[i]).norm());
  }
  EXPECT_LT(worst, 0.03) << "metres";
  // The same from the unmoved model: the frame does not depend on where the model was.
  Reconstruction at_origin = d.rec;
  TransformModel(at_origin, UprightTransform(at_origin, FitGround(at_origin), kHeight));
  double diff = 0;
  for (const auto& [id, im] : at_origin.images)
    diff = std::max(diff, (Centre(im) - Centre(moved.images.at(id))).norm());
  EXPECT_LT(diff, 1e-6);
}

TEST(Upright, KeepsTheUnitWithoutAHeightAndRefusesAScaleWithoutGround) {
  const Drive d = MakeDrive(false);  // walls and cars only: nothing the road would give
  Reconstruction moved = d.rec;
  TransformModel(moved, Moved());
  const GroundFit fit = FitGround(moved);
  EXPECT_EQ(fit.cameras_with_ground, 0u);
  EXPECT_EQ(fit.camera_height, 0.0);
  EXPECT_THROW(UprightTransform(moved, fit, kHeight), Error);
  EXPECT_DOUBLE_EQ(UprightTransform(moved, fit, 0).scale, 1.0);
}

}  // namespace
}  // namespace mvtm
