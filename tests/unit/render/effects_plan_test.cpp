// libcore/render/effects_plan: the plan and its reasons from hand-built surveys, and the
// hole/coverage survey of a view against hand-counted pixels of a half-plane.
#include "render/effects_plan.h"

#include <gtest/gtest.h>

#include <cmath>

#include "gl_suite.h"
#include "render/context.h"
#include "render/renderer.h"

namespace mvtm {
namespace {

// A PTM job whose projectors differ from the poses, several admissible, masks and holes.
SceneSurvey Everything() {
  SceneSurvey s;
  s.projectors_requested = 3;
  s.projector_differs = true;
  s.several_admissible = true;
  s.mask_example = "A_0001.png";
  s.frames_surveyed = 4;
  s.frames_with_holes = 1;
  s.hole_example = "A_0002.png";
  s.min_coverage = 0.25;
  s.seen_example = "A_0003.png";
  return s;
}

TEST(EffectsPlan, EverythingTheSceneCallsForIsOn) {
  const SceneSurvey s = Everything();
  const EffectsPlan p = PlanEffects(s);
  EXPECT_TRUE(p.ptm);
  EXPECT_EQ(p.projectors, 3);
  EXPECT_TRUE(p.occlusion);
  EXPECT_TRUE(p.masks);
  EXPECT_TRUE(p.skybox);
  EXPECT_TRUE(p.blend);
  EXPECT_TRUE(p.fill);
  EXPECT_TRUE(p.seen);
  EXPECT_EQ(p.Defines(),
            (std::vector<std::string>{"MVTM_MAX_PROJECTORS 3", "MVTM_PTM", "MVTM_OCCLUSION",
                                      "MVTM_MASKS", "MVTM_SKYBOX", "MVTM_BLEND", "MVTM_SEEN"}));
  const auto j = ExplainEffects(s, p);
  EXPECT_EQ(j["fill"]["reason"],
            "1 of 4 frames see no surface somewhere: where no projector sees sky there either, the "
            "pixels are filled from their surroundings (push-pull), never the constant "
            "background");
  EXPECT_EQ(j["masks"]["reason"], "selected projector A_0001.png has masked pixels");
  EXPECT_EQ(j["skybox"]["reason"],
            "1 of 4 frames see no surface somewhere (e.g. A_0002.png); at infinity (no sparse "
            "points give the scene's far end)");
  EXPECT_EQ(j["seen_surfaces"]["reason"],
            "selected projector A_0003.png has densify's map of what its photo saw (stereo/): "
            "where the first 1 projector(s) saw a surface on a pixel's ray nearer than the mesh's "
            "point by more than 0.05 of its depth and within 32 px of parallax (a pole, a trunk, "
            "a canopy, a near vehicle the fused mesh eroded or tore), the pixel takes that "
            "projector's colour there; on the ground only depths of confidence >= 0.6 (a road "
            "marking matched a period off would tear)");
  EXPECT_EQ(j["several_projectors"]["reason"],
            "up to 3 projectors per pixel, nearest first, then vertex colours; the first projector "
            "covers as "
            "little as 25.0 % of a view");
}

TEST(EffectsPlan, SkyAtTheScenesFarEndUnlessTold) {
  // The skybox's distance: the scene's far end by default (-1), the user's when given, infinity
  // (0) when asked for or when the model has no points; none without a skybox.
  SceneSurvey s = Everything();
  s.scene_far = 125.5;
  EXPECT_EQ(PlanEffects(s).sky_distance, 125.5);
  EXPECT_EQ(ExplainEffects(s, PlanEffects(s))["skybox"]["reason"],
            "1 of 4 frames see no surface somewhere (e.g. A_0002.png); at 125.5, the scene's far "
            "end (98th percentile of the distances its images see their sparse points at), so far "
            "scenery beyond the mesh keeps its parallax");
  s.sky_distance = 40;
  EXPECT_EQ(PlanEffects(s).sky_distance, 40);
  s.sky_distance = 0;
  EXPECT_EQ(PlanEffects(s).sky_distance, 0);
  s.sky_distance = -1;
  s.no_skybox = true;
  EXPECT_FALSE(PlanEffects(s).skybox);
  EXPECT_EQ(PlanEffects(s).sky_distance, 0);
}

TEST(EffectsPlan, NothingTheSceneDoesNotCallFor) {
  SceneSurvey s;  // one projector, the pose itself, no masks, no holes
  const EffectsPlan p = PlanEffects(s);
  EXPECT_EQ(p.projectors, 1);
  EXPECT_FALSE(p.occlusion || p.masks || p.skybox || p.blend || p.fill || p.seen);
  EXPECT_EQ(p.Defines(), (std::vector<std::string>{"MVTM_MAX_PROJECTORS 1", "MVTM_PTM"}));
  const auto j = ExplainEffects(s, p);
  EXPECT_EQ(j["occlusion"]["reason"], "every projector is the render pose itself");
  EXPECT_EQ(j["blend"]["reason"], "a single projector per pixel");
  EXPECT_EQ(j["fill"]["reason"], "every pixel of every frame sees the mesh");
  EXPECT_EQ(j["masks"]["reason"], "no selected projector has a non-empty mask");
  EXPECT_EQ(j["skybox"]["reason"], "every pixel of every frame sees the mesh");
  EXPECT_EQ(j["several_projectors"]["reason"], "no frame has more than one admissible projector");
  EXPECT_EQ(j["seen_surfaces"]["reason"], "every projector is the render pose itself");
  SceneSurvey other = s;  // projectors elsewhere, none with densify's map
  other.projector_differs = true;
  EXPECT_FALSE(PlanEffects(other).seen);
  EXPECT_EQ(ExplainEffects(other, PlanEffects(other))["seen_surfaces"]["reason"],
            "no selected projector has densify's map (stereo/)");
  EXPECT_TRUE(j["clip_test"]["on"]);
  EXPECT_TRUE(j["reverse_projection_rejection"]["on"]);
}

TEST(EffectsPlan, UserSwitchesWinAndSayWhy) {
  SceneSurvey s = Everything();
  s.no_occlusion = s.no_masks = s.no_skybox = s.no_fill = s.no_seen = true;
  s.projectors_requested = 1;
  const EffectsPlan p = PlanEffects(s);
  EXPECT_FALSE(p.occlusion || p.masks || p.skybox || p.fill || p.seen);
  EXPECT_EQ(ExplainEffects(s, p)["seen_surfaces"]["reason"], "turned off by --no-seen-surfaces");
  EXPECT_EQ(p.projectors, 1);
  const auto j = ExplainEffects(s, p);
  EXPECT_EQ(j["occlusion"]["reason"], "turned off by --no-occlusion");
  EXPECT_EQ(j["masks"]["reason"], "turned off by --no-masks");
  EXPECT_EQ(j["skybox"]["reason"], "turned off by --no-skybox");
  EXPECT_EQ(j["several_projectors"]["reason"],
            "--projectors 1 (vertex colours where it does not reach)");
  EXPECT_EQ(j["fill"]["reason"],
            "turned off by --no-fill (constant background where nothing is seen)");
  SceneSurvey b = Everything();
  b.no_blend = true;
  const EffectsPlan q = PlanEffects(b);
  EXPECT_FALSE(q.blend);
  EXPECT_EQ(q.projectors, 3);
  EXPECT_EQ(ExplainEffects(b, q)["blend"]["reason"],
            "turned off by --no-blend (the first projector that sees a point)");
}

TEST(EffectsPlan, VertexModeTurnsEveryProjectiveEffectOff) {
  SceneSurvey s = Everything();
  s.ptm = false;
  const EffectsPlan p = PlanEffects(s);
  EXPECT_FALSE(p.ptm || p.occlusion || p.masks || p.skybox || p.blend || p.fill || p.seen);
  EXPECT_EQ(p.Defines(), (std::vector<std::string>{"MVTM_MAX_PROJECTORS 1"}));
  const auto j = ExplainEffects(s, p);
  for (const char* e :
       {"reverse_projection_rejection", "clip_test", "occlusion", "several_projectors", "blend",
        "masks", "skybox", "fill", "seen_surfaces"}) {
    EXPECT_FALSE(j[e]["on"]) << e;
    EXPECT_EQ(j[e]["reason"], "vertex-colour mode") << e;
  }
  EXPECT_TRUE(j["vertex_colour_fallback"]["on"]);
}

TEST(EffectsPlan, SurveyKeepsTheFirstHoleAndTheLeastCoverage) {
  SceneSurvey s;
  AddToSurvey(s, {0, 100, 80}, "a");
  AddToSurvey(s, {5, 95, 19}, "b");
  AddToSurvey(s, {7, 93, 93}, "c");
  AddToSurvey(s, {10, 0, 0}, "d");  // no surface: coverage undefined, not counted
  EXPECT_EQ(s.frames_surveyed, 4u);
  EXPECT_EQ(s.frames_with_holes, 3u);
  EXPECT_EQ(s.hole_example, "b");
  EXPECT_DOUBLE_EQ(s.min_coverage, 0.2);
}

// Camera at the origin looking down +z, 40×20 px, f = 20, c = (20, 10); the half-plane x ≥ 0 at
// z = 10 fills exactly the image columns u ≥ 20 (pixel centres 20.5 .. 39.5): 400 surface
// pixels, 400 holes.
class SurveyViewTest : public GlSuite {};

Mesh HalfPlane() {
  Mesh m;
  m.vertices = {{0, -100, 10}, {100, -100, 10}, {100, 100, 10}, {0, 100, 10}};
  m.faces = {{0, 1, 2}, {0, 2, 3}};
  return m;
}

View At(double x) {
  return View{ParseCameraSpec("PINHOLE 40 20 20 20 20 10"),
              Rigid3d(Eigen::Quaterniond::Identity(), {-x, 0, 0})};
}

TEST_F(SurveyViewTest, HolesSurfaceAndCoverageAreCountedPerPixel) {
  Renderer r(HalfPlane());
  const View v = At(0);
  ViewCoverage alone = SurveyView(r, v, nullptr);
  EXPECT_EQ(alone.holes, 400u);
  EXPECT_EQ(alone.surface, 400u);
  EXPECT_EQ(alone.covered, 0u);
  // The same pose as projector covers every surface pixel.
  const View same = At(0);
  EXPECT_EQ(SurveyView(r, v, &same).covered, 400u);
  // A projector 10 to the left sees the plane's points at u = 2x + 40 ≥ 40: outside its image.
  const View left = At(-10);
  EXPECT_EQ(SurveyView(r, v, &left).covered, 0u);
  // 10 to the right: u = 2x, and the surface pixels see x = (u − 20)/2 ∈ [0.25, 9.75]: all inside.
  const View right = At(10);
  EXPECT_EQ(SurveyView(r, v, &right).covered, 400u);
}

}  // namespace
}  // namespace mvtm
