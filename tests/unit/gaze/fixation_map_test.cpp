// Fixations onto the mesh and their AOIs (gaze/fixation_map.h), on hand-built geometry: a ground
// plane and a wall ahead of a camera looking along +x.
#include "gaze/fixation_map.h"

#include <gtest/gtest.h>

#include <cmath>

#include "base/error.h"
#include "gaze_scene.h"

namespace mvtm {
namespace {

using gaze_test::LookAlongX;
using gaze_test::Pinhole;

Mesh Scene() { return gaze_test::Scene(3); }

Fixation At(double start, double end, double x, double y) {
  Fixation f;
  f.start = start;
  f.end = end;
  f.x = x;
  f.y = y;
  return f;
}

struct Stage {
  MeshRaycaster mesh{Scene()};
  Camera render = Pinhole(100, 100, 50);
  FrameClock clock{{0, 1}};
  std::vector<Rigid3d> w2c = {LookAlongX({0, 0, 1.5}), LookAlongX({-1, 0, 1.5})};
  ScreenGeometry screen;
  std::vector<SourceView> views = {{"photo", Pinhole(100, 100, 50), LookAlongX({0, 0, 1.5})}};
  Stage() {
    screen.width_px = 200;  // the render shown at twice its size
    screen.height_px = 200;
    screen.px_per_degree = 10;
  }
  ShownFrames Shown() const { return {clock, w2c, render, screen}; }
};

TEST(FixationMap, FrameAtTheMiddlePointOnTheMeshAndItsSources) {
  const Stage s;
  // Screen centre at frame 0: the wall at 5 m; at frame 1 (camera 1 m back) at 6 m. Below the
  // centre the ground; above the wall's top nothing.
  const std::vector<Fixation> fixations = {At(0.2, 0.6, 100, 100), At(0.8, 1.4, 100, 100),
                                           At(1.1, 1.3, 100, 190), At(0.1, 0.3, 100, 2)};
  const auto m = MapFixations(fixations, s.Shown(), s.mesh, s.views, nullptr, {});
  ASSERT_EQ(m.size(), 4u);
  EXPECT_EQ(m[0].frame, 0u);
  EXPECT_TRUE(m[0].hit);
  EXPECT_NEAR(m[0].X.x(), 5, 1e-9);
  EXPECT_NEAR(m[0].X.z(), 1.5, 1e-9);
  EXPECT_NEAR(m[0].distance, 5, 1e-9);
  ASSERT_EQ(m[0].sources.size(), 1u);
  EXPECT_NEAR(m[0].sources[0].u, 50, 1e-6);
  EXPECT_NEAR(m[0].sources[0].depth, 5, 1e-9);
  EXPECT_EQ(m[1].frame, 1u);  // middle 1.1
  EXPECT_NEAR(m[1].distance, 6, 1e-9);
  EXPECT_EQ(m[2].frame, 1u);
  EXPECT_TRUE(m[2].hit);
  EXPECT_NEAR(m[2].X.z(), 0, 1e-9);  // the ground
  EXPECT_FALSE(m[3].hit);
  EXPECT_TRUE(std::isnan(m[3].distance));
  EXPECT_TRUE(m[3].sources.empty());
  // A fixation after the last frame's display time (1 + the median interval 1).
  EXPECT_THROW(MapFixations({At(2.5, 2.7, 1, 1)}, s.Shown(), s.mesh, s.views, nullptr, {}), Error);
}

TEST(FixationMap, AoisFromBoxesLabelsOrNone) {
  const Stage s;
  const std::vector<Fixation> fixations = {At(0.2, 0.6, 100, 100), At(0.2, 0.6, 100, 190),
                                           At(0.1, 0.3, 100, 2)};
  auto m = MapFixations(fixations, s.Shown(), s.mesh, s.views, nullptr, {});
  AoiBox wall{"wall", Eigen::AlignedBox3d(Eigen::Vector3d(4.9, -5, 0), Eigen::Vector3d(5.1, 5, 3))};
  AssignAois(m, {wall}, nullptr);
  EXPECT_EQ(m[0].aoi, "wall");
  EXPECT_EQ(m[1].aoi, "outside");
  EXPECT_EQ(m[2].aoi, "no-surface");
  // Labels: the class at the fixation's pixel in the photo; a photo without labels: unknown.
  Image labels(100, 100, 1, 8, 3);  // road
  for (int x = 0; x < 100; ++x)
    for (int y = 40; y < 60; ++y) labels.at(x, y) = 1;  // building in the middle rows
  AssignAois(m, {}, [&](size_t) { return &labels; });
  ASSERT_EQ(m[0].sources.size(), 1u);
  EXPECT_NEAR(m[0].sources[0].v, 50, 1e-6);
  EXPECT_EQ(m[0].aoi, "building");  // the pixel (50, 50)
  EXPECT_EQ(m[1].aoi, "road");      // (50, 95)
  EXPECT_EQ(m[2].aoi, "no-surface");
  AssignAois(m, {}, [](size_t) { return nullptr; });
  EXPECT_EQ(m[0].aoi, "unknown");
  AssignAois(m, {}, nullptr);
  EXPECT_EQ(m[0].aoi, "surface");
}

}  // namespace
}  // namespace mvtm
