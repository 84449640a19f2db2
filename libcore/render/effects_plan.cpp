#include "render/effects_plan.h"

#include <algorithm>
#include <cmath>
#include <cstdio>

#include "render/renderer.h"

namespace mvtm {

std::vector<std::string> EffectsPlan::Defines() const {
  std::vector<std::string> d;
  d.push_back("MVTM_MAX_PROJECTORS " + std::to_string(std::max(1, projectors)));
  if (ptm) d.push_back("MVTM_PTM");
  if (occlusion) d.push_back("MVTM_OCCLUSION");
  if (masks) d.push_back("MVTM_MASKS");
  if (skybox) d.push_back("MVTM_SKYBOX");
  if (exposure) d.push_back("MVTM_EXPOSURE");
  if (ptm && blend && projectors > 1) d.push_back("MVTM_BLEND");
  if (ptm && seen) d.push_back("MVTM_SEEN");
  return d;
}

ViewCoverage SurveyView(Renderer& renderer, const View& v, const View* first) {
  return CoverageOf(renderer.RenderDepth(v), v, first);
}

ViewCoverage CoverageOf(const Image& d, const View& v, const View* first) {
  const Camera& cam = v.camera;
  ViewCoverage c;
  const float* z = d.data.data();
  if (!first) {
    for (size_t p = 0; p < d.pixels(); ++p) c.holes += !std::isfinite(z[p]);
    c.surface = d.pixels() - c.holes;
    return c;
  }
  // The point at pixel (x, y) and depth z in the first projector's camera, x_p = z·(M·ray) + b
  // with ray = ((x + ½ − cx)/fx, (y + ½ − cy)/fy, 1) the render camera's pinhole ray, is inside
  // its image when 0 ≤ fx·x_p/z_p + cx < W (likewise y), tested without dividing by z_p > 0.
  const Camera& pc = first->camera;
  const Eigen::Matrix3d M = first->world_to_camera.R() * v.world_to_camera.R().transpose();
  const Eigen::Vector3d b = first->world_to_camera * v.world_to_camera.Centre();
  const Eigen::Vector3d dx = M.col(0) / cam.fx();
  const double W = double(pc.width), H = double(pc.height);
  const double fx = pc.fx(), fy = pc.fy(), cx = pc.cx(), cy = pc.cy();
  for (int y = 0; y < d.height; ++y) {
    const Eigen::Vector3d row =
        M * Eigen::Vector3d((0.5 - cam.cx()) / cam.fx(), (y + 0.5 - cam.cy()) / cam.fy(), 1);
    for (int x = 0; x < d.width; ++x, ++z) {
      if (!std::isfinite(*z)) {
        ++c.holes;
        continue;
      }
      ++c.surface;
      const Eigen::Vector3d xp = double(*z) * (row + double(x) * dx) + b;
      if (!(xp.z() > 0)) continue;
      const double u = fx * xp.x() + cx * xp.z(), w = fy * xp.y() + cy * xp.z();
      c.covered += u >= 0 && w >= 0 && u < W * xp.z() && w < H * xp.z();
    }
  }
  return c;
}

void AddToSurvey(SceneSurvey& s, const ViewCoverage& v, const std::string& name) {
  ++s.frames_surveyed;
  if (v.holes) {
    ++s.frames_with_holes;
    if (s.hole_example.empty()) s.hole_example = name;
  }
  if (v.surface) s.min_coverage = std::min(s.min_coverage, double(v.covered) / double(v.surface));
}

EffectsPlan PlanEffects(const SceneSurvey& s) {
  EffectsPlan plan;
  plan.ptm = s.ptm;
  plan.bias = s.bias;
  plan.projectors = s.ptm && s.several_admissible ? s.projectors_requested : 1;
  plan.occlusion = s.ptm && !s.no_occlusion && s.projector_differs;
  plan.masks = s.ptm && !s.no_masks && !s.mask_example.empty();
  plan.skybox = s.ptm && !s.no_skybox && s.frames_with_holes > 0;
  if (plan.skybox) plan.sky_distance = s.sky_distance >= 0 ? s.sky_distance : s.scene_far;
  plan.exposure = s.ptm && !s.no_exposure && !s.exposure_example.empty();
  plan.blend = plan.projectors > 1 && !s.no_blend;
  plan.weights = s.blend_weights;
  plan.fill = s.ptm && !s.no_fill && s.frames_with_holes > 0;
  plan.seen = s.ptm && !s.no_seen && s.projector_differs && !s.seen_example.empty();
  plan.seen_surfaces = s.seen_surfaces;
  plan.seen_surfaces.projectors = std::clamp(plan.seen_surfaces.projectors, 1, plan.projectors);
  return plan;
}

namespace {

std::string ShortDouble(double v) {
  char b[32];
  std::snprintf(b, sizeof b, "%g", v);
  return b;
}

std::string SkyDistanceReason(const SceneSurvey& s, const EffectsPlan& plan) {
  if (plan.sky_distance <= 0)
    return s.sky_distance == 0 ? "at infinity (--sky-distance 0)"
                               : "at infinity (no sparse points give the scene's far end)";
  if (s.sky_distance > 0) return "at " + ShortDouble(plan.sky_distance) + " (--sky-distance)";
  return "at " + ShortDouble(plan.sky_distance) +
         ", the scene's far end (98th percentile of the distances its images see their sparse "
         "points at), so far scenery beyond the mesh keeps its parallax";
}

nlohmann::json Choice(bool on, const std::string& why_on, const std::string& why_off) {
  return nlohmann::json{{"on", on}, {"reason", on ? why_on : why_off}};
}

nlohmann::json SeenChoice(const SceneSurvey& s, const EffectsPlan& plan,
                          const std::string& vertex_mode) {
  return Choice(plan.seen,
                "selected projector " + s.seen_example +
                    " has densify's map of what its photo saw (stereo/): where the first " +
                    std::to_string(plan.seen_surfaces.projectors) +
                    " projector(s) saw a surface on a pixel's ray nearer than the mesh's point by "
                    "more than " +
                    ShortDouble(plan.seen_surfaces.front) + " of its depth and within " +
                    ShortDouble(plan.seen_surfaces.reach) +
                    " px of parallax (a pole, a trunk, a canopy, a near vehicle the fused mesh "
                    "eroded or tore), the pixel takes that projector's colour there; on the "
                    "ground only depths of confidence >= " +
                    ShortDouble(plan.seen_surfaces.ground_confidence) +
                    " (a road marking matched a period off would tear)",
                !s.ptm                 ? vertex_mode
                : s.no_seen            ? "turned off by --no-seen-surfaces"
                : !s.projector_differs ? "every projector is the render pose itself"
                                       : "no selected projector has densify's map (stereo/)");
}

}  // namespace

nlohmann::json ExplainEffects(const SceneSurvey& s, const EffectsPlan& plan) {
  const std::string vertex_mode = "vertex-colour mode";
  char cov[64];
  std::snprintf(cov, sizeof cov, "%.1f %%", 100 * s.min_coverage);
  const std::string always = "always on in PTM: cheap and always correct";
  return {
      {"reverse_projection_rejection", Choice(s.ptm, always, vertex_mode)},
      {"clip_test", Choice(s.ptm, always, vertex_mode)},
      {"occlusion", Choice(plan.occlusion,
                           "projectors differ from the render poses, so the mesh can hide points "
                           "from them; relative bias " +
                               ShortDouble(s.bias),
                           !s.ptm           ? vertex_mode
                           : s.no_occlusion ? "turned off by --no-occlusion"
                                            : "every projector is the render pose itself")},
      {"several_projectors", Choice(plan.projectors > 1,
                                    "up to " + std::to_string(plan.projectors) +
                                        " projectors per pixel, nearest first, then vertex "
                                        "colours; the first projector covers as "
                                        "little as " +
                                        std::string(cov) + " of a view",
                                    !s.ptm ? vertex_mode
                                    : s.projectors_requested == 1
                                        ? "--projectors 1 (vertex colours where it does not reach)"
                                        : "no frame has more than one admissible projector")},
      {"blend",
       Choice(plan.blend,
              "several projectors see most points: each pixel blends those that see it, "
              "weighted by the angle between its ray and theirs (power " +
                  ShortDouble(plan.weights.power) + "), resolution (" +
                  ShortDouble(plan.weights.res_weight) +
                  " x (1 - the camera's distance / the projector's) rad), border "
                  "feathering (" +
                  ShortDouble(plan.weights.feather) + " px) and soft occlusion (" +
                  ShortDouble(plan.weights.soft) + ")",
              !s.ptm       ? vertex_mode
              : s.no_blend ? "turned off by --no-blend (the first projector that sees a point)"
                           : "a single projector per pixel")},
      {"vertex_colour_fallback",
       Choice(true, s.ptm ? "where no projector reaches" : vertex_mode, "")},
      {"masks", Choice(plan.masks, "selected projector " + s.mask_example + " has masked pixels",
                       !s.ptm       ? vertex_mode
                       : s.no_masks ? "turned off by --no-masks"
                                    : "no selected projector has a non-empty mask")},
      {"skybox",
       Choice(plan.skybox,
              std::to_string(s.frames_with_holes) + " of " + std::to_string(s.frames_surveyed) +
                  " frames see no surface somewhere (e.g. " + s.hole_example + "); " +
                  SkyDistanceReason(s, plan),
              !s.ptm        ? vertex_mode
              : s.no_skybox ? "turned off by --no-skybox"
                            : "every pixel of every frame sees the mesh")},
      {"fill",
       Choice(plan.fill,
              std::to_string(s.frames_with_holes) + " of " + std::to_string(s.frames_surveyed) +
                  " frames see no surface somewhere: where no projector sees sky there either, "
                  "the pixels are filled from their surroundings (push-pull), never the "
                  "constant background",
              !s.ptm      ? vertex_mode
              : s.no_fill ? "turned off by --no-fill (constant background where nothing is seen)"
                          : "every pixel of every frame sees the mesh")},
      {"exposure",
       Choice(plan.exposure,
              "selected projector " + s.exposure_example +
                  " was recorded at another exposure (exposure.tsv): its samples are brought to "
                  "the common one, and the render is recorded at the exposure of its nearest "
                  "projectors (inverse-square distance weights)",
              !s.ptm ? vertex_mode
              : s.no_exposure
                  ? "turned off by --no-exposure"
                  : "no exposure.tsv, or every selected projector at the common exposure")},
      {"seen_surfaces", SeenChoice(s, plan, vertex_mode)}};
}

}  // namespace mvtm
