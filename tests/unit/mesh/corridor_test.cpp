// libcore/mesh corridor against hand-built scenes whose answer is known without the corridor code:
// a straight road on a known plane with walls at known distances (seen through a rigid motion to
// UTM-sized coordinates), the same road driven the other way, no points at all, bad paths; and the
// area-weighted normals the corridor relies on (scene/mesh.h) on a shape worked out by hand.
#include "mesh/corridor.h"

#include <gtest/gtest.h>

#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>

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
