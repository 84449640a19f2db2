// MeshRaycaster against hits derived by hand on a 10 × 10 square in z = 0 (two triangles split
// along the diagonal y = x), at the origin and at a UTM-sized offset.
#include "raycast/mesh_raycaster.h"

#include <gtest/gtest.h>

#include "base/error.h"

namespace mvtm {
namespace {

// A(0,0,0) B(10,0,0) C(10,10,0) D(0,10,0); faces (A,B,C): y <= x, (A,C,D): y >= x. Optionally a
// second square at z = 2 over [0,5]² (faces 2 and 3).
Mesh Square(const Eigen::Vector3d& o, bool roof = false) {
  Mesh m;
  m.vertices = {o + Eigen::Vector3d(0, 0, 0), o + Eigen::Vector3d(10, 0, 0),
                o + Eigen::Vector3d(10, 10, 0), o + Eigen::Vector3d(0, 10, 0)};
  m.faces = {{0, 1, 2}, {0, 2, 3}};
  if (roof) {
    for (const auto& v : {Eigen::Vector3d(0, 0, 2), Eigen::Vector3d(5, 0, 2),
                          Eigen::Vector3d(5, 5, 2), Eigen::Vector3d(0, 5, 2)})
      m.vertices.push_back(o + v);
    m.faces.push_back({4, 5, 6});
    m.faces.push_back({4, 6, 7});
  }
  return m;
}

class RaycastTest : public ::testing::TestWithParam<Eigen::Vector3d> {
 protected:
  Eigen::Vector3d O() const { return GetParam(); }
  // Points are compared to 1e-8 absolute: double rounding at 5e6 is 9e-10.
  static constexpr double kTol = 1e-8;
};

TEST_P(RaycastTest, StraightDownHitsTheLowerTriangle) {
  const MeshRaycaster rc(Square(O()));
  const auto h = rc.Closest(O() + Eigen::Vector3d(2, 1, 5), Eigen::Vector3d(0, 0, -1));
  ASSERT_TRUE(h);
  EXPECT_EQ(h->triangle, 0u);
  EXPECT_NEAR(h->t, 5, 1e-12);
  // (2,1) = u·(10,0) + v·(10,10): v = 0.1, u = 0.1.
  EXPECT_NEAR(h->u, 0.1, 1e-12);
  EXPECT_NEAR(h->v, 0.1, 1e-12);
  EXPECT_LT((h->point - (O() + Eigen::Vector3d(2, 1, 0))).norm(), kTol);
  EXPECT_LT((h->normal - Eigen::Vector3d(0, 0, 1)).norm(), 1e-15);
}

TEST_P(RaycastTest, TIsInUnitsOfTheDirection) {
  const MeshRaycaster rc(Square(O()));
  const auto h = rc.Closest(O() + Eigen::Vector3d(1, 3, 2), Eigen::Vector3d(0, 0, -2));
  ASSERT_TRUE(h);
  EXPECT_EQ(h->triangle, 1u);
  EXPECT_NEAR(h->t, 1, 1e-12);
  // (1,3) = u·(10,10) + v·(0,10): u = 0.1, v = 0.2 (face A, C, D).
  EXPECT_NEAR(h->u, 0.1, 1e-12);
  EXPECT_NEAR(h->v, 0.2, 1e-12);
  EXPECT_LT((h->point - (O() + Eigen::Vector3d(1, 3, 0))).norm(), kTol);
}

TEST_P(RaycastTest, SlantedAndGrazingRays) {
  const MeshRaycaster rc(Square(O()));
  // Slope 1:10 from (-1,5,1): z = 0 at t = 10, x = 9.
  auto h = rc.Closest(O() + Eigen::Vector3d(-1, 5, 1), Eigen::Vector3d(1, 0, -0.1));
  ASSERT_TRUE(h);
  EXPECT_NEAR(h->t, 10, 1e-9);
  EXPECT_LT((h->point - (O() + Eigen::Vector3d(9, 5, 0))).norm(), kTol);
  // Grazing at 1e-4 and 1e-6 rad: from 1e-3 (1e-5) above, z = 0 at t = 10, x = 5. The expected
  // hit is computed from the origin as represented (at 5e6, the height 1e-5 is off by up to
  // 1e-9, which moves the hit by 1e-3 along a 1e-6 slope).
  for (double slope : {1e-4, 1e-6}) {
    const Eigen::Vector3d o = O() + Eigen::Vector3d(-5, 4, 10 * slope);
    const Eigen::Vector3d rel = o - O();  // exact (Sterbenz)
    const double t = rel.z() / slope;
    h = rc.Closest(o, Eigen::Vector3d(1, 0, -slope));
    ASSERT_TRUE(h) << slope;
    EXPECT_EQ(h->triangle, 0u);
    EXPECT_NEAR(h->t, t, 1e-6) << slope;
    EXPECT_NEAR(t, 10, 1e-3);
    EXPECT_LT((h->point - (O() + Eigen::Vector3d(rel.x() + t, rel.y(), 0))).norm(), 1e-6) << slope;
    EXPECT_NEAR(h->point.z() - O().z(), 0, kTol) << slope;
    EXPECT_NEAR(h->v, rel.y() / 10, 1e-6);  // (x, y) = u(10,0) + v(10,10)
    EXPECT_NEAR(h->u, (rel.x() + t - rel.y()) / 10, 1e-6);
  }
  // Parallel to the plane just above it, and pointing away: no hit.
  EXPECT_FALSE(rc.Closest(O() + Eigen::Vector3d(-5, 4, 1e-3), Eigen::Vector3d(1, 0, 0)));
  EXPECT_FALSE(rc.Closest(O() + Eigen::Vector3d(2, 1, 5), Eigen::Vector3d(0, 0, 1)));
}

TEST_P(RaycastTest, IntervalAndClosestOfTwoSurfaces) {
  const MeshRaycaster rc(Square(O(), true));
  const Eigen::Vector3d down(0, 0, -1);
  auto h = rc.Closest(O() + Eigen::Vector3d(2, 1, 5), down);
  ASSERT_TRUE(h);
  EXPECT_EQ(h->triangle, 2u);
  EXPECT_NEAR(h->t, 3, 1e-12);
  h = rc.Closest(O() + Eigen::Vector3d(2, 1, 5), down, 3.5);  // past the roof
  ASSERT_TRUE(h);
  EXPECT_EQ(h->triangle, 0u);
  EXPECT_NEAR(h->t, 5, 1e-12);
  h = rc.Closest(O() + Eigen::Vector3d(7, 1, 5), down);  // beside the roof
  ASSERT_TRUE(h);
  EXPECT_NEAR(h->t, 5, 1e-12);
  EXPECT_FALSE(rc.Closest(O() + Eigen::Vector3d(2, 1, 5), down, 0, 2.9));
  // From below, the back faces are hit too.
  h = rc.Closest(O() + Eigen::Vector3d(2, 1, -1), Eigen::Vector3d(0, 0, 1));
  ASSERT_TRUE(h);
  EXPECT_NEAR(h->t, 1, 1e-12);
  EXPECT_LT((h->normal - Eigen::Vector3d(0, 0, 1)).norm(), 1e-15);
}

TEST_P(RaycastTest, Occlusion) {
  const MeshRaycaster rc(Square(O(), true));
  const Eigen::Vector3d from = O() + Eigen::Vector3d(7, 1, 5), down(0, 0, -1);
  EXPECT_FALSE(rc.Occluded(from, down, 0, 4.9));
  EXPECT_TRUE(rc.Occluded(from, down, 0, 5.1));
  EXPECT_TRUE(rc.Occluded(O() + Eigen::Vector3d(2, 1, 5), down, 0, 3.1));     // the roof
  EXPECT_FALSE(rc.Occluded(O() + Eigen::Vector3d(2, 1, 5), down, 3.1, 4.9));  // between
  // A sight line from (−1, 1, 1) to (11, 1, 1) above the ground: clear.
  EXPECT_FALSE(rc.Occluded(O() + Eigen::Vector3d(-1, 1, 1), Eigen::Vector3d(12, 0, 0), 0, 1));
}

TEST_P(RaycastTest, TheDiagonalEdgeIsWatertight) {
  const MeshRaycaster rc(Square(O()));
  for (int k = 1; k < 1000; ++k) {
    const double x = k / 100.0;
    const auto h = rc.Closest(O() + Eigen::Vector3d(x, x, 1), Eigen::Vector3d(0, 0, -1));
    ASSERT_TRUE(h) << x;
    EXPECT_NEAR(h->t, 1, 1e-12);
    EXPECT_LT((h->point - (O() + Eigen::Vector3d(x, x, 0))).norm(), kTol);
    EXPECT_GE(h->u, 0);
    EXPECT_GE(h->v, 0);
    EXPECT_LE(h->u + h->v, 1 + 1e-15);
  }
}

INSTANTIATE_TEST_SUITE_P(Offsets, RaycastTest,
                         ::testing::Values(Eigen::Vector3d(0, 0, 0),
                                           Eigen::Vector3d(451000.25, 5e6 + 0.125, 120.5),
                                           Eigen::Vector3d(5e6, 5e6, 5e6)));

TEST(Raycast, RecentresOnTheMeshBounds) {
  const MeshRaycaster rc(Square(Eigen::Vector3d(5e6, 5e6, 0)));
  EXPECT_EQ(rc.centre(), Eigen::Vector3d(5e6 + 5, 5e6 + 5, 0));
  EXPECT_EQ(rc.triangles(), 2u);
}

TEST(Raycast, EmptyMeshHitsNothing) {
  const MeshRaycaster rc{Mesh{}};
  EXPECT_FALSE(rc.Closest(Eigen::Vector3d(0, 0, 1), Eigen::Vector3d(0, 0, -1)));
  EXPECT_FALSE(rc.Occluded(Eigen::Vector3d(0, 0, 1), Eigen::Vector3d(0, 0, -1), 0, 10));
}

TEST(Raycast, BadFaceIndexIsAnError) {
  Mesh m = Square(Eigen::Vector3d::Zero());
  m.faces.push_back({0, 1, 7});
  EXPECT_THROW(MeshRaycaster{m}, Error);
}

TEST(Raycast, DegenerateTrianglesAreNeverHit) {
  Mesh m;
  m.vertices = {{0, 0, 0}, {1, 1, 0}, {2, 2, 0}};  // collinear
  m.faces = {{0, 1, 2}};
  const MeshRaycaster rc(m);
  EXPECT_FALSE(rc.Closest(Eigen::Vector3d(1, 1, 1), Eigen::Vector3d(0, 0, -1)));
}

}  // namespace
}  // namespace mvtm
