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
