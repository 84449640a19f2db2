// Screen → world ray → mesh → source photographs (gaze/mapping.h), on hand-built geometry: a
// ground plane and a wall, cameras placed by hand.
#include "gaze/mapping.h"

#include <gtest/gtest.h>

#include <cmath>

#include "base/error.h"
#include "gaze_scene.h"

namespace mvtm {
namespace {

using gaze_test::LookAlongX;
using gaze_test::Pinhole;

Mesh Scene() { return gaze_test::Scene(10); }

TEST(FrameClock, LastFrameWithTimeNotAfterT) {
  const FrameClock c({0, 0.1, 0.2, 0.4});  // median interval 0.1: the last ends at 0.5
  EXPECT_EQ(*c.FrameAt(0), 0u);
  EXPECT_EQ(*c.FrameAt(0.0999), 0u);
  EXPECT_EQ(*c.FrameAt(0.1), 1u);
  EXPECT_EQ(*c.FrameAt(0.39), 2u);
  EXPECT_EQ(*c.FrameAt(0.49), 3u);
  EXPECT_FALSE(c.FrameAt(0.5));
  EXPECT_FALSE(c.FrameAt(-0.01));
  EXPECT_FALSE(c.FrameAt(NAN));
  EXPECT_THROW(FrameClock({0, 0.1, 0.1}), Error);
}

TEST(ScreenRay, ScreenIsTheRenderScaledToIt) {
  const Camera cam = Pinhole(100, 50, 50);
  const Rigid3d pose = LookAlongX({0, 0, 2}, 1);
  // The screen centre is the optical axis; the screen's right edge at mid-height is the image's
  // (u = 100: 50 px right of cx, at f = 50: 45°), whatever the screen's size.
  for (double scale : {1.0, 3.0, 19.2}) {
    const WorldRay c = ScreenRay(cam, pose, 100 * scale, 50 * scale, 50 * scale, 25 * scale);
    EXPECT_NEAR((c.origin - Eigen::Vector3d(0, 0, 2)).norm(), 0, 1e-15);
    EXPECT_NEAR((c.direction - Eigen::Vector3d(1, 0, 0)).norm(), 0, 1e-15);
    const WorldRay r = ScreenRay(cam, pose, 100 * scale, 50 * scale, 100 * scale, 25 * scale);
    EXPECT_NEAR((r.direction - Eigen::Vector3d(1, -1, 0)).norm(), 0, 1e-15);
  }
  // Through the mesh: the ray to the ground 20 m ahead from 2 m up.
  const MeshRaycaster mesh(Scene());
  const Rigid3d far = LookAlongX({30, 0, 2}, 1);
  // Pixel row for a 0.1 slope down: v = cy + f·0.1 = 30.
  const WorldRay g = ScreenRay(cam, far, 100, 50, 50, 30);
  const auto hit = mesh.Closest(g.origin, g.direction);
  ASSERT_TRUE(hit);
  EXPECT_NEAR((hit->point - Eigen::Vector3d(50, 0, 0)).norm(), 0, 1e-12);
  EXPECT_NEAR(hit->t, 20, 1e-12);  // the render camera's depth
}

TEST(SourcesOf, OccludedBehindAndBelowAreNotSources) {
  const MeshRaycaster mesh(Scene());
  const Camera cam = Pinhole(100, 50, 50);
  const Eigen::Vector3d X(10, 0, 0), up(0, 0, 1), viewer(20, 0, 2);
  const std::vector<SourceView> views = {
      {"hidden", cam, LookAlongX({0, 0, 2}, 1)},     // the wall at x = 5 is in the way
      {"sees", cam, LookAlongX({20, 0, 2}, -1)},     // looks back at X: seen
      {"behind", cam, LookAlongX({20, 0, 2}, 1)},    // X is behind it
      {"below", cam, LookAlongX({20, 0, -2}, -1)},   // under the ground: its back side
      {"beside", cam, LookAlongX({20, 40, 2}, -1)},  // X is outside the image
  };
  const auto hits = SourcesOf(X, up, viewer, views, mesh, nullptr, {});
  ASSERT_EQ(hits.size(), 1u);
  EXPECT_EQ(hits[0].view, 1u);
  // X in "sees": 10 m ahead, 2 m down: u = cx, v = cy + 50·0.2 = 35.
  EXPECT_NEAR(hits[0].u, 50, 1e-12);
  EXPECT_NEAR(hits[0].v, 35, 1e-12);
  EXPECT_NEAR(hits[0].depth, 10, 1e-12);
  EXPECT_FALSE(hits[0].by_depth);

  // Depth maps decide when given: the hidden view's map holds the wall (5 m) at X's pixel.
  Image wall(100, 50, 1, 32, 5.f), open(100, 50, 1, 32, 10.f);
  const DepthLookup maps = [&](size_t i) -> const Image* { return i == 0 ? &wall : &open; };
  const auto d = SourcesOf(X, up, viewer, views, mesh, maps, {});
  ASSERT_EQ(d.size(), 1u);
  EXPECT_EQ(d[0].view, 1u);
  EXPECT_TRUE(d[0].by_depth);
  // A map 1.5 % short of the point hides it at a 1 % tolerance, not at 2 % (the map alone
  // decides: both views X projects into, in front of the surface, count).
  Image short_map(100, 50, 1, 32, 10 / 1.015f);
  const DepthLookup s = [&](size_t) -> const Image* { return &short_map; };
  EXPECT_TRUE(SourcesOf(X, up, viewer, views, mesh, s, {0.01, 1e-3}).empty());
  EXPECT_EQ(SourcesOf(X, up, viewer, views, mesh, s, {0.02, 1e-3}).size(), 2u);
}

}  // namespace
}  // namespace mvtm
