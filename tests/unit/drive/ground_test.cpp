// The car on synthetic meshes: a flat plane, a 1:10 ramp (pitch and roll by hand), a bumpy
// height field whose vertices lie under the wheels, a UTM-sized model in other units, and
// leaving the mesh.
#include "drive/ground.h"

#include <gtest/gtest.h>

#include <cmath>
#include <functional>

#include "base/error.h"

namespace mvtm {
namespace {

// A height field z = f(x, y) on a grid over [x0, x1] × [y0, y1] with spacing `cell`, moved by
// `origin` and scaled by `scale` (world = origin + scale · local).
Mesh HeightField(const std::function<double(double, double)>& f, double x0, double x1, double y0,
                 double y1, double cell, const Eigen::Vector3d& origin = Eigen::Vector3d::Zero(),
                 double scale = 1) {
  Mesh m;
  const int nx = static_cast<int>(std::lround((x1 - x0) / cell));
  const int ny = static_cast<int>(std::lround((y1 - y0) / cell));
  for (int j = 0; j <= ny; ++j)
    for (int i = 0; i <= nx; ++i) {
      const double x = x0 + i * cell, y = y0 + j * cell;
      m.vertices.push_back(origin + scale * Eigen::Vector3d(x, y, f(x, y)));
    }
  auto id = [&](int i, int j) { return static_cast<uint32_t>(j * (nx + 1) + i); };
  for (int j = 0; j < ny; ++j)
    for (int i = 0; i < nx; ++i) {
      m.faces.push_back({id(i, j), id(i + 1, j), id(i + 1, j + 1)});
      m.faces.push_back({id(i, j), id(i + 1, j + 1), id(i, j + 1)});
    }
  return m;
}

RoadFrame Frame(const Eigen::Vector3d& origin, double scale) {
  RoadFrame f;
  f.origin = origin;
  f.scale = scale;
  return f;
}

TEST(Ground, FlatRoad) {
  const MeshRaycaster mesh(HeightField([](double, double) { return 0.0; }, -50, 50, -50, 50, 2));
  CarGeometry car;
  car.camera_offset = {1.2, 0.3, 1.4};
  GroundPlacer placer(mesh, Frame({0, 0, 1.65}, 1), car);
  for (double heading : {0.0, 0.7, -2.5}) {
    const Placement p = placer.Place({3, -4, heading}, 0);
    const Eigen::Vector3d f(std::cos(heading), std::sin(heading), 0), l(-f.y(), f.x(), 0);
    const Eigen::Vector3d want =
        Eigen::Vector3d(3, -4, 0) + 1.2 * f + 0.3 * l + Eigen::Vector3d(0, 0, 1.4);
    EXPECT_LT((p.camera_to_world.t - want).norm(), 1e-12);
    EXPECT_NEAR(p.pitch, 0, 1e-15);
    EXPECT_NEAR(p.roll, 0, 1e-15);
    const Eigen::Matrix3d R = p.camera_to_world.R();
    EXPECT_LT((R.col(2) - f).norm(), 1e-12);                          // looks forward
    EXPECT_LT((R.col(1) - Eigen::Vector3d(0, 0, -1)).norm(), 1e-12);  // y down
    EXPECT_LT((R.col(0) + l).norm(), 1e-12);                          // x right
  }
}

TEST(Ground, RampGivesPitchOrRollAndKeepsTheCameraHeight) {
  const double g = 0.1;  // z = 0.1 x
  const MeshRaycaster mesh(
      HeightField([g](double x, double) { return g * x; }, -50, 50, -50, 50, 2.5));
  CarGeometry car;
  car.camera_offset = {0, 0, 1.65};
  const Eigen::Vector3d n = Eigen::Vector3d(-g, 0, 1).normalized();  // the plane's normal
  {
    GroundPlacer placer(mesh, Frame({0, 0, 1.65}, 1), car);
    const Placement p = placer.Place({5, 2, 0}, 0);  // heading +x: uphill
    EXPECT_NEAR(p.pitch, std::atan(g), 1e-12);
    EXPECT_NEAR(p.roll, 0, 1e-12);
    EXPECT_NEAR(p.camera_to_world.t.dot(n), 1.65, 1e-12);  // perpendicular height
    EXPECT_LT((p.rear_ground - Eigen::Vector3d(5, 2, 0.5)).norm(), 1e-12);
  }
  {
    GroundPlacer placer(mesh, Frame({0, 0, 1.65}, 1), car);
    const Placement p = placer.Place({5, 2, M_PI / 2}, 0);  // heading +y: left side is −x, lower
    EXPECT_NEAR(p.pitch, 0, 1e-12);
    EXPECT_NEAR(p.roll, -std::atan(g), 1e-12);
    EXPECT_NEAR(p.camera_to_world.t.dot(n), 1.65, 1e-12);
  }
}

// Bumps z = A sin(k x) sampled on a grid whose lines pass under both axles: the contacts are
// mesh vertices, so the fitted plane is known by hand.
TEST(Ground, BumpsUnderTheWheels) {
  const double A = 0.08, k = 2 * M_PI / 7;
  auto f = [&](double x, double) { return A * std::sin(k * x); };
  const MeshRaycaster mesh(HeightField(f, -10, 40, -10, 10, 0.1));
  CarGeometry car;  // wheelbase 2.7, track 1.6
  car.camera_offset = {0, 0, 1.65};
  GroundPlacer placer(mesh, Frame({0, 0, 1.65}, 1), car);
  for (int i = 0; i <= 200; ++i) {
    const double x = i * 0.1;
    const Placement p = placer.Place({x, 0, 0}, i * 0.01);
    // Vertex heights are float-free doubles of f at the grid x (x, x + 2.7 on the grid).
    const double hr = A * std::sin(k * (std::round(x * 10) / 10));
    const double hf = A * std::sin(k * (std::round((x + 2.7) * 10) / 10));
    const double slope = (hf - hr) / 2.7;
    EXPECT_NEAR(p.pitch, std::atan(slope), 1e-9) << x;
    const Eigen::Vector3d up = Eigen::Vector3d(-slope, 0, 1).normalized();
    const Eigen::Vector3d want = Eigen::Vector3d(x, 0, hr) + 1.65 * up;
    EXPECT_LT((p.camera_to_world.t - want).norm(), 1e-9) << x;
  }
}

TEST(Ground, UtmModelInOtherUnits) {
  const Eigen::Vector3d origin(451000.5, 5410000.25, 120);
  const double scale = 0.2;  // model units per metre
  const MeshRaycaster mesh(
      HeightField([](double x, double) { return 0.1 * x; }, -50, 50, -50, 50, 2.5, origin, scale));
  CarGeometry car;
  car.camera_offset = {0.5, 0, 1.65};
  GroundPlacer placer(mesh, Frame(origin + scale * Eigen::Vector3d(0, 0, 1.65), scale), car);
  const Placement p = placer.Place({5, 2, 0}, 0);
  const Eigen::Vector3d n = Eigen::Vector3d(-0.1, 0, 1).normalized();
  EXPECT_NEAR((p.camera_to_world.t - origin).dot(n), scale * 1.65, 1e-9);
  EXPECT_NEAR(p.pitch, std::atan(0.1), 1e-9);
  EXPECT_LT((p.rear_ground - (origin + scale * Eigen::Vector3d(5, 2, 0.5))).norm(), 1e-9);
}

TEST(Ground, LeavingTheMeshNamesTheTimeAndTheWheel) {
  const MeshRaycaster mesh(HeightField([](double, double) { return 0.0; }, -10, 10, -10, 10, 2));
  GroundPlacer placer(mesh, Frame({0, 0, 1.65}, 1), CarGeometry{});
  EXPECT_NO_THROW(placer.Place({0, 0, 0}, 0));
  try {
    placer.Place({8, 0, 0}, 3.5);
    FAIL() << "no error";
  } catch (const Error& e) {
    EXPECT_EQ(std::string(e.what()),
              "leaves the mesh at t = 3.5 s: no surface under the front-left wheel at x = 10.70, "
              "y = 0.80 m from the start");
  }
}

TEST(Ground, FramesAndRecordedCameras) {
  // A level camera looking along +y at (1, 2, 3): forward +y, down −z, right +x.
  Eigen::Matrix3d c2w;
  c2w.col(0) = Eigen::Vector3d(1, 0, 0);
  c2w.col(1) = Eigen::Vector3d(0, 0, -1);
  c2w.col(2) = Eigen::Vector3d(0, 1, 0);
  const Rigid3d w2c = Rigid3d(Eigen::Quaterniond(c2w), Eigen::Vector3d(1, 2, 3)).Inverse();
  const Eigen::Vector3d up = RecordedUp({w2c, w2c});
  EXPECT_LT((up - Eigen::Vector3d(0, 0, 1)).norm(), 1e-15);
  const RoadFrame f = FrameAtCamera(w2c, up, 2.0);
  EXPECT_LT((f.x_axis - Eigen::Vector3d(0, 1, 0)).norm(), 1e-15);
  EXPECT_LT((f.y_axis - Eigen::Vector3d(-1, 0, 0)).norm(), 1e-15);
  const PlanarPose p = PlanarCamera(f, w2c);
  EXPECT_NEAR(p.x, 0, 1e-15);
  EXPECT_NEAR(p.y, 0, 1e-15);
  EXPECT_NEAR(p.heading, 0, 1e-15);
  // 2 units per metre: the point 4 units ahead is 2 m ahead.
  EXPECT_NEAR(f.ToPlane(Eigen::Vector3d(1, 6, 0)).x(), 2, 1e-15);
  EXPECT_NEAR(f.Height(Eigen::Vector3d(1, 6, 0)), -1.5, 1e-15);
  const MeshRaycaster mesh(HeightField([](double, double) { return 0.0; }, -10, 10, -10, 10, 2));
  EXPECT_EQ(CameraHeights(mesh, {w2c}, up), std::vector<double>{3.0});
  const Rigid3d far = Rigid3d(Eigen::Quaterniond(c2w), Eigen::Vector3d(100, 2, 3)).Inverse();
  EXPECT_TRUE(CameraHeights(mesh, {far}, up).empty());
  // The rear axle 1.5 m behind a camera foot at (0, 0) heading +y: (0, −1.5).
  CarGeometry car;
  car.camera_offset = {1.5, 0, 1.2};
  const PlanarPose r = RearAxleUnder({0, 0, M_PI / 2}, car);
  EXPECT_NEAR(r.x, 0, 1e-15);
  EXPECT_NEAR(r.y, -1.5, 1e-15);
}

}  // namespace
}  // namespace mvtm
