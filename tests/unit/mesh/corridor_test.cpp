// libcore/mesh corridor against hand-built scenes whose answer is known without the corridor code:
// a straight road on a known plane with walls at known distances (seen through a rigid motion to
// UTM-sized coordinates), the same road driven the other way, no points at all, bad paths; and the
// area-weighted normals the corridor relies on (scene/mesh.h) on a shape worked out by hand; and
// scale-freedom: a curved road with scattered points and the same road under a similarity.
#include "mesh/corridor.h"

#include <gtest/gtest.h>

#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <limits>
#include <random>

#include "base/error.h"

namespace mvtm {
namespace {

// The road of the scene: cameras every 2.51 from x = 0 to x = 50.2 at height kHeight above the
// plane z = 0, looking along +x (or −x); ground points on the plane for |y| ≤ 3.25, walls at
// y = +10.1 (left when looking along +x) and y = −6 from z = 1.5 to 8.5 (clear of the ground
// band, |z| < 1).
constexpr double kHeight = 2.0, kLength = 50.2, kLeftY = 10.1, kRightY = -6.0;
constexpr int kImages = 21;

// A rigid motion of the whole scene: a tilt and a turn, to UTM-sized coordinates.
struct Motion {
  Eigen::Matrix3d R = (Eigen::AngleAxisd(0.7, Eigen::Vector3d::UnitZ()) *
                       Eigen::AngleAxisd(0.05, Eigen::Vector3d(1, 2, 0).normalized()))
                          .toRotationMatrix();
  Eigen::Vector3d t{512345.25, 5412345.5, 120.0};
  Eigen::Vector3d Apply(const Eigen::Vector3d& p) const { return R * p + t; }
  Eigen::Vector3d Undo(const Eigen::Vector3d& p) const { return R.transpose() * (p - t); }
};

// Camera at `c` looking along `forward` (horizontal), camera y down (−z).
Rigid3d Looking(const Eigen::Vector3d& c, const Eigen::Vector3d& forward, const Motion& m) {
  const Eigen::Vector3d down(0, 0, -1), right = down.cross(forward);
  Eigen::Matrix3d w2c;  // rows: the camera axes in the (moved) world
  w2c.row(0) = (m.R * right).transpose();
  w2c.row(1) = (m.R * down).transpose();
  w2c.row(2) = (m.R * forward).transpose();
  const Eigen::Quaterniond q(w2c);
  return Rigid3d(q, -(q * m.Apply(c)));
}

Reconstruction Road(bool backwards, bool with_points, const Motion& m) {
  Reconstruction rec;
  for (int i = 0; i < kImages; ++i) {
    ImageRecord im;
    im.id = uint32_t(i + 1);
    im.name = "f" + std::to_string(100 + i);
    const Eigen::Vector3d c(kLength * i / (kImages - 1), 0, kHeight);
    im.world_to_camera = Looking(c, Eigen::Vector3d(backwards ? -1 : 1, 0, 0), m);
    rec.images[im.id] = im;
  }
  if (!with_points) return rec;
  auto add = [&](double x, double y, double z) {
    Point3D p;
    p.id = rec.points3D.size() + 1;
    p.xyz = m.Apply(Eigen::Vector3d(x, y, z));
    rec.points3D[p.id] = p;
  };
  for (int i = 0; i <= 50; ++i) {
    for (int j = 0; j < 14; ++j) add(i, -3.25 + 0.5 * j, 0);
    for (int k = 0; k < 8; ++k) add(i, kLeftY, 1.5 + k), add(i, kRightY, 1.5 + k);
  }
  return rec;
}

// Every vertex index of the corridor's parts, from its documented layout.
struct Layout {
  size_t stations, cols, rows;
  size_t GroundEnd() const { return stations * (cols + 1); }
  size_t LeftEnd() const { return GroundEnd() + stations * (rows + 1); }
};

void ExpectStraightRoad(const Corridor& c, const Motion& m, bool backwards) {
  // 110.2 of path (50.2 + 2 × 30 extension) every 0.5: 221 stations; span 10.1 + 6 = 16.1 over
  // 0.5: 33 columns; 10 / 0.5: 20 rows per wall.
  const Layout l{221, 33, 20};
  EXPECT_NEAR(c.path_length, kLength, 1e-6);
  ASSERT_EQ(c.stations, l.stations);
  ASSERT_EQ(c.mesh.vertices.size(), l.LeftEnd() + l.stations * (l.rows + 1));
  EXPECT_EQ(c.mesh.faces.size(), (l.stations - 1) * (l.cols + 2 * l.rows) * 2);
  EXPECT_NEAR(c.camera_height, kHeight, 1e-6);
  // Looking along −x, left is −y.
  EXPECT_NEAR(c.left_wall, backwards ? -kRightY : kLeftY, 1e-6);
  EXPECT_NEAR(c.right_wall, backwards ? kLeftY : -kRightY, 1e-6);
  ASSERT_TRUE(c.mesh.has_normals());
  EXPECT_FALSE(c.mesh.has_colors());
  double xmin = 1e300, xmax = -1e300, max_off_plane = 0, max_normal_err = 0;
  for (size_t v = 0; v < c.mesh.vertices.size(); ++v) {
    const Eigen::Vector3d p = m.Undo(c.mesh.vertices[v]);
    Eigen::Vector3d want = m.R.col(2);  // ground: up; walls: facing the road (towards y = 0)
    if (v < l.GroundEnd()) {
      max_off_plane = std::max(max_off_plane, std::abs(p.z()));
      xmin = std::min(xmin, p.x()), xmax = std::max(xmax, p.x());
    } else {
      const bool left_wall = v < l.LeftEnd();
      EXPECT_NEAR(p.y(), left_wall != backwards ? kLeftY : kRightY, 1e-6) << v;
      EXPECT_GT(p.z(), -1e-6) << v;
      EXPECT_LT(p.z(), 10 + 1e-6) << v;
      want = m.R * Eigen::Vector3d(0, p.y() > 0 ? -1 : 1, 0);
    }
    // Walls have their own vertices, so every vertex normal is that of a flat part.
    max_normal_err = std::max(max_normal_err, (c.mesh.normals[v].cast<double>() - want).norm());
  }
  // The ground lies on the plane of the points (float normals: 1e-6).
  EXPECT_LT(max_off_plane, 1e-6);
  EXPECT_LT(max_normal_err, 1e-6);
  // It runs from 30 before the first camera along the road for 110 (the last station; 0.5
  // apart) — past the last camera by 30 less the 0.2 remainder.
  const double start = backwards ? kLength + 30 : -30, end = backwards ? start - 110 : start + 110;
  EXPECT_NEAR(xmin, std::min(start, end), 1e-6);
  EXPECT_NEAR(xmax, std::max(start, end), 1e-6);
}

TEST(Corridor, StraightRoadLiesOnThePointsPlaneWithWallsAtThePoints) {
  const Motion m;
  const Corridor c = BuildCorridor(Road(false, true, m), CorridorOptions());
  // Ground points within width/4 = 2 of the path: 8 lateral positions × 51.
  EXPECT_EQ(c.ground_points, 8u * 51u);
  EXPECT_GT(c.refined_vertices, 0u);
  ExpectStraightRoad(c, m, false);
}

TEST(Corridor, DrivingTheOtherWaySwapsTheWalls) {
  const Motion m;
  const Corridor c = BuildCorridor(Road(true, true, m), CorridorOptions());
  ExpectStraightRoad(c, m, true);
}

TEST(Corridor, WithoutPointsTheDefaultsHold) {
  const Motion m;
  for (double width : {8.0, 14.0, 20.0}) {
    CorridorOptions o;
    o.width = width;
    o.resolution = 1;
    const Corridor c = BuildCorridor(Road(false, false, m), o);
    EXPECT_EQ(c.ground_points, 0u);
    EXPECT_EQ(c.camera_height, 1.65);  // KITTI's
    EXPECT_EQ(c.refined_vertices, 0u);
    // 8 unless the road is wider: at least width/2 + 1.
    const double wall = std::max(8.0, width / 2 + 1);
    EXPECT_NEAR(c.left_wall, wall, 1e-9);
    EXPECT_NEAR(c.right_wall, wall, 1e-9);
    // Ground 1.65 below the cameras: z = 2 − 1.65 everywhere.
    const size_t ground = c.stations * (size_t(std::ceil(2 * wall / o.resolution - 1e-9)) + 1);
    for (size_t v = 0; v < ground; ++v)
      ASSERT_NEAR(m.Undo(c.mesh.vertices[v]).z(), kHeight - 1.65, 1e-6) << v;
    EXPECT_NEAR(std::abs(m.Undo(c.mesh.vertices[ground]).y()), wall, 1e-6);
  }
}

TEST(Corridor, BadPathsThrow) {
  const Motion m;
  Reconstruction one = Road(false, true, m);
  one.images.erase(std::next(one.images.begin()), one.images.end());
  EXPECT_THROW(BuildCorridor(one, CorridorOptions()), Error);
  Reconstruction still = Road(false, true, m);
  for (auto& [id, im] : still.images)
    im.world_to_camera = still.images.begin()->second.world_to_camera;
  EXPECT_THROW(BuildCorridor(still, CorridorOptions()), Error);
}

// A curved road (radius 150, 40 cameras about 1.1 apart, 1.6 above the road, level) with
// scattered points: the road, a pavement, facades, and clutter; no two values on a boundary of
// the corridor's rules except by chance.
Reconstruction CurvedRoad() {
  std::mt19937_64 rng(7);
  auto uniform = [&](double a, double b) { return a + (b - a) * double(rng() >> 11) * 0x1p-53; };
  const double radius = 150;
  auto at = [&](double s, double d, double z) {  // arc length, offset to the left, height
    const double a = s / radius;
    return Eigen::Vector3d((radius - d) * std::sin(a), radius - (radius - d) * std::cos(a), z);
  };
  Reconstruction rec;
  const Motion none{Eigen::Matrix3d::Identity(), Eigen::Vector3d::Zero()};
  for (int i = 0; i < 40; ++i) {
    ImageRecord im;
    im.id = uint32_t(i + 1);
    im.name = "c" + std::to_string(100 + i);
    const double s = 1.1 * i + uniform(-0.1, 0.1), a = s / radius + uniform(-0.01, 0.01);
    const Eigen::Vector3d forward(std::cos(a), std::sin(a), 0);
    im.world_to_camera = Looking(at(s, uniform(-0.2, 0.2), 1.6), forward.normalized(), none);
    rec.images[im.id] = im;
  }
  auto add = [&](const Eigen::Vector3d& x) {
    Point3D p;
    p.id = rec.points3D.size() + 1;
    p.xyz = x;
    rec.points3D[p.id] = p;
  };
  for (int i = 0; i < 3000; ++i) {
    const double s = uniform(-20, 70), kind = uniform(0, 1);
    if (kind < 0.5)
      add(at(s, uniform(-5, 5), uniform(-0.05, 0.05)));  // the road
    else if (kind < 0.6)
      add(at(s, uniform(5, 7), 0.15 + uniform(-0.05, 0.05)));  // a pavement
    else if (kind < 0.95)
      add(at(s, kind < 0.8 ? uniform(8, 9) : uniform(-12.5, -11), uniform(0, 14)));  // facades
    else
      add(at(s, uniform(-40, 40), uniform(-3, 20)));  // clutter
  }
  return rec;
}

// The similarity x → s·R·x + t applied to a model: points and poses (w2c' = w2c ∘ the inverse).
Reconstruction Transformed(const Reconstruction& rec, double s, const Motion& m) {
  Reconstruction out = rec;
  const Eigen::Quaterniond qr(m.R);
  for (auto& [id, im] : out.images) {
    const Eigen::Quaterniond q = NormalizedQuaternion(im.world_to_camera.q) * qr.conjugate();
    im.world_to_camera = Rigid3d(q, -(q * (s * (m.R * im.world_to_camera.Centre()) + m.t)));
  }
  for (auto& [id, p] : out.points3D) p.xyz = s * (m.R * p.xyz) + m.t;
  return out;
}

// The corridor of a model scaled by 0.2, rotated and moved to UTM coordinates, built with the unit
// scaled by 0.2, is the first corridor under the same similarity, vertex by vertex.
TEST(Corridor, ScaledModelWithScaledUnitGivesTheScaledCorridor) {
  const double s = 0.2;
  const Motion m{Eigen::Matrix3d(Eigen::AngleAxisd(2.0, Eigen::Vector3d(1, -2, 5).normalized())),
                 Eigen::Vector3d(451000, 5410000, 120)};
  const Reconstruction a = CurvedRoad(), b = Transformed(a, s, m);
  CorridorOptions oa;
  oa.width = 9;  // other than the defaults, so every option is seen scaled
  oa.wall_height = 12;
  oa.resolution = 0.7;
  CorridorOptions ob = oa;
  ob.unit = s;
  const Corridor ca = BuildCorridor(a, oa), cb = BuildCorridor(b, ob);
  ASSERT_EQ(ca.stations, cb.stations);
  ASSERT_EQ(ca.mesh.vertices.size(), cb.mesh.vertices.size());
  ASSERT_EQ(ca.mesh.faces, cb.mesh.faces);
  EXPECT_GT(ca.ground_points, 0u);
  EXPECT_EQ(ca.ground_points, cb.ground_points);
  EXPECT_EQ(ca.refined_vertices, cb.refined_vertices);
  // The scene's sizes scale; relative to them, double rounding of UTM-sized coordinates: an ulp
  // of |t| (≈ 1e-9) over the corridor's few hundred operations per vertex, 1e3 ulps.
  const double ulp = std::numeric_limits<double>::epsilon() * m.t.norm(), tol = 1e3 * ulp;
  EXPECT_NEAR(cb.path_length, s * ca.path_length, tol);
  EXPECT_NEAR(cb.camera_height, s * ca.camera_height, tol);
  EXPECT_NEAR(cb.left_wall, s * ca.left_wall, tol);
  EXPECT_NEAR(cb.right_wall, s * ca.right_wall, tol);
  double worst = 0, worst_normal = 0;
  for (size_t v = 0; v < ca.mesh.vertices.size(); ++v) {
    const Eigen::Vector3d want = s * (m.R * ca.mesh.vertices[v]) + m.t;
    worst = std::max(worst, (cb.mesh.vertices[v] - want).norm());
    const Eigen::Vector3d n = m.R * ca.mesh.normals[v].cast<double>();
    worst_normal = std::max(worst_normal, (cb.mesh.normals[v].cast<double>() - n).norm());
  }
  std::printf("[corridor similarity] %zu vertices, worst %.3g (tolerance %.3g), normals %.3g\n",
              ca.mesh.vertices.size(), worst, tol, worst_normal);
  EXPECT_LT(worst, tol);
  EXPECT_LT(worst_normal, 1e-5);  // float normals: a few float ulps
}

// Two triangles on the edge (0,0,0)–(1,0,0): one in z = 0 of area 1 facing +z, one in y = 0 of
// area 1.5 facing −y. Shared vertices get (0, −3, 2)/√13, the others their face's normal.
TEST(Corridor, VertexNormalsAreAreaWeighted) {
  Mesh m;
  m.vertices = {{0, 0, 0}, {1, 0, 0}, {0, 2, 0}, {0, 0, -3}};
  m.faces = {{0, 1, 2}, {1, 0, 3}};
  m.ComputeNormals();
  const Eigen::Vector3f shared = Eigen::Vector3f(0, -3, 2) / std::sqrt(13.f);
  EXPECT_LT((m.normals[0] - shared).norm(), 1e-6f);
  EXPECT_LT((m.normals[1] - shared).norm(), 1e-6f);
  EXPECT_LT((m.normals[2] - Eigen::Vector3f(0, 0, 1)).norm(), 1e-6f);
  EXPECT_LT((m.normals[3] - Eigen::Vector3f(0, -1, 0)).norm(), 1e-6f);
}

}  // namespace
}  // namespace mvtm
