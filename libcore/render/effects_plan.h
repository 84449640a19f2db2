// mvtm — the effects plan: which rendering effects a job needs, decided from its inputs, and why.
//
// DESIGN.md "simulate only the effects a scene calls for". A tool first surveys its inputs
// (SceneSurvey: the projectors each pose selected, the masks they carry, whether views see
// holes), then PlanEffects() switches on exactly the effects the scene calls for and
// ExplainEffects() gives the reason for each choice (ptmrender --explain). The renderer compiles
// one shader variant per plan (EffectsPlan::Defines).
//
// The survey must cover every render pose of the job, not just a shard's, so that every split of
// the work plans alike (shards byte-identical to one run).
//
// Thread safety: plain values and pure functions, except SurveyView, which renders (GL thread).
#pragma once

#include <algorithm>
#include <array>
#include <cstddef>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

namespace mvtm {

// How blending weighs the projectors that see a point: visibility (soft occlusion) × border
// feathering × (1 / (penalty + 1e-3 rad))^power, penalty = the angle between the render ray and
// the projector's + res_weight · max(0, 1 − d_render / d_proj). The user's knobs (ptmrender
// --blend-power, --feather, --res-weight, --soft), carried unchanged into the plan.
struct BlendWeights {
  double power = 2;         // sharpness p (large: the best-angle projector alone)
  double feather = 16;      // pixels over which a projector fades out at its image border
  double res_weight = 0.1;  // R: R·(1 − d_render/d_proj) rad for a farther projector (R/2 at 2×)
  double soft = 0.01;       // soft occlusion width, relative (visibility 1 → 0 over d·soft)
};

// Seen surfaces (MVTM_SEEN): a projector's own depth map of what its photo saw (densify's,
// stereo/NAME.exr) is right for thin poles, trunks, canopies and near vehicles in the view that
// saw them even where the fused mesh tore them (per-view geometry; Hedman et al. 2016). Each
// surface pixel's ray is marched through the first `projectors` projectors' maps in front of the
// mesh's point; the first place where the ray passes behind what a projector saw, by more than
// `front` of the mesh's depth in front of it, gives the pixel that projector's colour there.
// The search reaches `reach` pixels of parallax in front of the mesh's point (a sample every 2):
// far enough for the silhouettes the fused mesh eroded or tore, not so far that a wrong depth
// near the camera in one photo's map takes pixels (measured: 32 px the best on KITTI 06 and
// mkroad, within 0.001 of 8 px on KITTI 01; longer reaches cost time and gain nothing). The
// user's knobs (ptmrender --seen-front, --seen-reach, --seen-projectors).
struct SeenSurfaces {
  double front = 0.05;  // relative: a seen surface counts when nearer than depth·(1 − front)
  double reach = 32;    // pixels of parallax searched in front of the mesh's point, > 0
  int projectors = 1;   // the first projectors, in rank order, searched
  double jump = 0.1;    // relative depth step between successive samples that is an edge
  // On the ground (a pixel whose mesh normal is within 37 degrees of the render camera's up)
  // only densify's pixels of at least this confidence count: a repetitive road marking's wrong
  // depths would otherwise tear it (measured on KITTI 01: 0.6 mends the chevrons of frame 20).
  double ground_confidence = 0.6;
};

// The effects a frame is rendered with (one shader variant per distinct plan).
struct EffectsPlan {
  bool ptm = true;         // false: vertex colours only
  int projectors = 1;      // projectors tried in rank order (≥ 1)
  bool occlusion = false;  // test against projector depth maps
  bool masks = false;      // skip masked projector texels
  bool skybox = false;     // background from projectors (else constant colour)
  // The skybox's distance from the render camera in model units (0: at infinity, rotation only):
  // far scenery the mesh does not reach keeps some parallax when the camera moves.
  double sky_distance = 0;
  bool exposure = false;  // projectors' samples brought to the common exposure (gain, offset)
  double bias = 0.005;    // relative occlusion bias: occluded when z > d·(1 + bias)
  // Blending (MVTM_BLEND): every projector that sees a point, weighted (BlendWeights); off: the
  // first projector in rank order that sees the point (thesis Alg. 3).
  bool blend = false;
  BlendWeights weights;
  // Pixels no projector, no vertex and no sky colours (background) are filled from their
  // surroundings (push-pull) instead of the constant background.
  bool fill = false;
  // Surfaces the projectors' photos saw in front of the mesh (SeenSurfaces; needs their maps).
  bool seen = false;
  SeenSurfaces seen_surfaces;
  std::array<float, 3> background{0, 0, 0};  // 0..255

  // The shader's #define switches for this plan.
  std::vector<std::string> Defines() const;
  // How many projectors, first in rank order, the seen surfaces search (0 without them): the
  // ones whose densify maps are read and uploaded.
  int SeenProjectors() const {
    return ptm && seen ? std::clamp(seen_surfaces.projectors, 1, std::max(projectors, 1)) : 0;
  }
};

// What the inputs of a job say, and what the user asked for.
struct SceneSurvey {
  // The request.
  bool ptm = true;                                                 // false: vertex-colour mode
  int projectors_requested = 4;                                    // K
  double bias = 0.005;                                             // relative occlusion bias
  bool no_occlusion = false, no_masks = false, no_skybox = false;  // the user's switches
  bool no_exposure = false;                                        // the user's switch
  bool no_blend = false, no_fill = false;                          // the user's switches
  bool no_seen = false;                                            // the user's switch
  SeenSurfaces seen_surfaces;                                      // the user's knobs
  double sky_distance = -1;  // --sky-distance: < 0 the scene's far end (scene_far), 0 infinity
  BlendWeights blend_weights;
  // The inputs.
  bool projector_differs = false;   // some selected projector is not the pose it serves
  bool several_admissible = false;  // some pose has more than one admissible projector
  std::string mask_example;         // a selected projector with set mask pixels ("": none)
  std::string exposure_example;     // a selected projector not at the common exposure ("": none)
  std::string seen_example;         // a selected projector with densify's map ("": none)
  size_t frames_surveyed = 0;       // poses whose views were surveyed for holes
  size_t frames_with_holes = 0;     // ... of which see no surface somewhere
  std::string hole_example;         // one of those ("": none)
  double min_coverage = 1.0;        // least share of a view's surface its first projector covers
  double scene_far = 0;             // the scene's far end (SceneFarEnd: 0 when no points)
};

// The --sky-distance option's help (ptmrender, simulate): SceneSurvey::sky_distance.
inline constexpr const char* kSkyDistanceHelp =
    "Skybox distance in model units: negative (-1) the scene's far end (98th percentile of the "
    "distances at which the images see their sparse points), 0 at infinity";
class Renderer;
struct View;
struct Image;

// One view's share of the survey: pixels with no surface, and of the surface pixels those that
// `first_projector` (when given) sees inside its image, in front of it.
struct ViewCoverage {
  size_t holes = 0, surface = 0, covered = 0;
};
// Renders the view's depth (every pixel: a single hole pixel must plan alike in every split).
ViewCoverage SurveyView(Renderer& renderer, const View& view, const View* first_projector);
// The same from the view's depth (RenderDepth's, or a Render's with_depth), pinhole cameras.
ViewCoverage CoverageOf(const Image& depth, const View& view, const View* first_projector);
// Adds a surveyed view (named `name` in explanations) to the survey.
void AddToSurvey(SceneSurvey& survey, const ViewCoverage& view, const std::string& name);

// The plan the survey calls for.
EffectsPlan PlanEffects(const SceneSurvey& survey);

// {"reverse_projection_rejection": {"on": true, "reason": "..."}, "clip_test": ..., "occlusion":
// ..., "several_projectors": ..., "blend": ..., "vertex_colour_fallback": ..., "masks": ...,
// "skybox": ..., "fill": ..., "exposure": ..., "seen_surfaces": ...}
nlohmann::json ExplainEffects(const SceneSurvey& survey, const EffectsPlan& plan);

}  // namespace mvtm
