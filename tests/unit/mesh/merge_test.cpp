// mesh/merge: the proxy's ground lowered and its walls moved back by hand-derived amounts.
#include "mesh/merge.h"

#include <gtest/gtest.h>

#include "base/error.h"

namespace mvtm {
namespace {

// A ground quad at z = 0 (normal +z) and a wall quad at y = 5 facing −y (towards the path).
Mesh Proxy() {
  Mesh m;
  m.vertices = {{0, -1, 0}, {4, -1, 0}, {4, 1, 0}, {0, 1, 0},
                {0, 5, 0},  {4, 5, 0},  {4, 5, 3}, {0, 5, 3}};
  m.faces = {{0, 1, 2}, {0, 2, 3}, {4, 5, 6}, {4, 6, 7}};
  m.ComputeNormals();
  return m;
}

TEST(Merge, GroundLoweredWallsMovedBackDenseKept) {
  Mesh dense;
  dense.vertices = {{1, 4.9, 1}, {2, 4.9, 1}, {1, 4.9, 2}};
  dense.faces = {{0, 1, 2}};
  const Mesh proxy = Proxy();
  ASSERT_NEAR(proxy.normals[4].y(), -1, 1e-6);  // the wall faces the path
  MergeReport r;
  const Mesh m = MergeProxyBehind(dense, proxy, {0, 0, 1}, 0.25, 2.0, &r);
  EXPECT_EQ(r.ground_faces, 2u);
  EXPECT_EQ(r.wall_faces, 2u);
  ASSERT_EQ(m.faces.size(), 5u);
  EXPECT_EQ(m.faces[0], dense.faces[0]);
  ASSERT_EQ(m.vertices.size(), 3u + 8u);
  for (size_t i = 0; i < 3; ++i) EXPECT_EQ(m.vertices[i], dense.vertices[i]);
  for (uint32_t v : {3u, 4u, 5u, 6u})
    EXPECT_NEAR(m.vertices[v].z(), -0.25, 1e-12);  // ground, lowered
  for (uint32_t v : {7u, 8u, 9u, 10u})
    EXPECT_NEAR(m.vertices[v].y(), 7.0, 1e-6);  // wall, 5 + 2 back
  EXPECT_TRUE(m.has_normals());
}

TEST(Merge, AWallMovedBackTakesItsFootDownSoNoGapOpensAtTheGroundsEdge) {
  // The corridor's case: the ground reaches the wall (y = 5), whose own vertices sit on the
  // ground's edge. Moved back by 2, the wall's foot also goes 2 down: a ray from a camera 1.65
  // above the ground at y = 0 that grazes the ground's edge (2, 5, 0) goes on to y = 7 at
  // z = -1.65 · 2 / 5 = -0.66, on the wall (z from -2 to 3), not through a gap to nothing.
  Mesh proxy;
  proxy.vertices = {{0, -1, 0}, {4, -1, 0}, {4, 5, 0}, {0, 5, 0},
                    {0, 5, 0},  {4, 5, 0},  {4, 5, 3}, {0, 5, 3}};
  proxy.faces = {{0, 1, 2}, {0, 2, 3}, {4, 5, 6}, {4, 6, 7}};
  proxy.ComputeNormals();
  const Mesh m = MergeProxyBehind(Mesh(), proxy, {0, 0, 1}, 0, 2.0);
  ASSERT_EQ(m.vertices.size(), 8u);
  for (uint32_t v : {4u, 5u}) {  // the foot: back and down
    EXPECT_NEAR(m.vertices[v].y(), 7.0, 1e-6);
    EXPECT_NEAR(m.vertices[v].z(), -2.0, 1e-6);
  }
  for (uint32_t v : {6u, 7u}) {  // the top: back only
    EXPECT_NEAR(m.vertices[v].y(), 7.0, 1e-6);
    EXPECT_NEAR(m.vertices[v].z(), 3.0, 1e-6);
  }
  const double z_at_wall = 1.65 - 1.65 * 7.0 / 5.0;
  EXPECT_GT(z_at_wall, m.vertices[4].z());
  EXPECT_LT(z_at_wall, m.vertices[6].z());
  // Without walls moved back nothing moves down.
  const Mesh same = MergeProxyBehind(Mesh(), proxy, {0, 0, 1}, 0, 0);
  EXPECT_NEAR(same.vertices[4].z(), 0, 1e-12);
}

TEST(Merge, NoWallsAndBadInput) {
  MergeReport r;
  const Mesh m = MergeProxyBehind(Mesh(), Proxy(), {0, 0, 2}, 0, -1, &r);
  EXPECT_EQ(r.ground_faces, 2u);
  EXPECT_EQ(r.wall_faces, 0u);
  EXPECT_EQ(m.faces.size(), 2u);
  EXPECT_EQ(m.vertices.size(), 4u);  // shared ground vertices stay shared
  EXPECT_THROW(MergeProxyBehind(Mesh(), Proxy(), {0, 0, 0}, 0, 1), Error);
  EXPECT_THROW(MergeProxyBehind(Mesh(), Proxy(), {0, 0, 1}, -1, 1), Error);
  Mesh bare = Proxy();
  bare.normals.clear();
  EXPECT_THROW(MergeProxyBehind(Mesh(), bare, {0, 0, 1}, 0, 1), Error);
}

}  // namespace
}  // namespace mvtm
