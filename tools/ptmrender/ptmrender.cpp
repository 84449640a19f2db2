#include "ptmrender.h"

#include <malloc.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <future>
#include <limits>
#include <map>
#include <memory>
#include <nlohmann/json.hpp>
#include <optional>
#include <ostream>
#include <set>

#include "base/atomic_file.h"
#include "base/error.h"
#include "base/text.h"
#include "cli/progress.h"
#include "image/async_writer.h"
#include "image/mask.h"
#include "io/colmap_model.h"
#include "io/exposure_tsv.h"
#include "io/mesh_io.h"
#include "io/trajectory.h"
#include "render/context.h"
#include "render/effects_plan.h"
#include "run/ledger.h"
#include "workspace/projector_sources.h"
#include "workspace/road.h"
#include "workspace/road_locator.h"
#include "workspace/road_meshes.h"
#include "workspace/workspace.h"

namespace mvtm {

namespace {

// The seen surfaces' switch and knobs (SeenSurfaces).
void DeclareSeenOptions(OptionTable& t, PtmRenderOptions& o) {
  t.Flag("--no-seen-surfaces", &o.no_seen,
         "Ignore stereo/ (densify's maps): never take what a projector's photo saw in front of "
         "the mesh");
  t.Real("--seen-front", &o.seen.front,
         "Seen surfaces: a projector's seen surface takes a pixel when nearer than the mesh's "
         "depth*(1-F)")
      .Range(0, 1, false, true);
  t.Real("--seen-reach", &o.seen.reach,
         "Seen surfaces: pixels of parallax searched in front of the mesh's point (a sample "
         "every 2): more reach nearer surfaces and cost more")
      .Range(0, 4096, true);
  t.Real("--seen-ground-conf", &o.seen.ground_confidence,
         "Seen surfaces: on the ground (mesh normal within 37 degrees of the camera's up) only "
         "densify's depths of at least this confidence count (0: every depth; a map without a "
         "confidence file counts as sure)")
      .Range(0, 1);
  t.Integer("--seen-projectors", &o.seen.projectors,
            "Seen surfaces: the first N projectors searched (at most --projectors)")
      .Range(1, 64);
}

}  // namespace

OptionTable DeclareOptions(PtmRenderOptions& o) {
  OptionTable t("ptmrender");
  t.Positional("WS", &o.workspace,
               "Workspace folder (sparse/, images/, mesh.ply; depth/, masks/, textures/ used "
               "when present), or a road (ROAD/Graph.txt): streamed fragment by fragment")
      .Dir();
  t.Positional("OUTDIR", &o.outdir, "Folder for the frames (NAME.png)").Dir();
  t.Text("--poses", &o.poses, "Render poses: COLMAP images.txt, TUM or KITTI trajectory")
      .File()
      .Excludes("--at-images");
  t.Flag("--at-images", &o.at_images, "Render at the workspace's own image poses (the default)");
  t.Flag("--exclude-self", &o.exclude_self,
         "With --at-images: never use an image as a projector for its own pose");
  t.Real("--lateral", &o.lateral,
         "Move each pose sideways, metres to the left (+) or right (-): a lane change")
      .Alternative("0.5");
  t.Real("--yaw", &o.yaw,
         "Turn each pose, degrees to the left (+) or right (-), about the camera's up axis")
      .Alternative("3");
  t.Choice("--mode", &o.mode, kPtmModes, "ptm: project photographs; vertex: vertex colours only");
  t.Integer("--projectors", &o.projectors, "K: projectors tried per pixel, best first")
      .Range(1, 16);
  t.Real("--bias", &o.bias, "Occlusion bias, relative: occluded when z > depth*(1+B)")
      .Range(0, 1, false, true);
  t.Real("--max-heading", &o.selection.max_heading_deg, "Heading gate for projectors, degrees")
      .Range(0, 180, true);
  t.Real("--ahead-weight", &o.selection.ahead_weight,
         "Extra cost per metre a projector is ahead of the pose (0 = nearest pose)")
      .AtLeast(0);
  t.Flag("--no-occlusion", &o.no_occlusion, "Never test projector depth (off even when needed)");
  t.Flag("--no-skybox", &o.no_skybox, "Constant background instead of projected sky");
  t.Real("--sky-distance", &o.sky_distance, kSkyDistanceHelp).AtLeast(-1).Alternative("0");
  t.Flag("--no-masks", &o.no_masks, "Ignore masks/ (vehicles are projected too)");
  t.Flag("--no-exposure", &o.no_exposure,
         "Ignore exposure.tsv (each projector at its own exposure)");
  t.Flag("--no-blend", &o.no_blend,
         "Take the first projector that sees a point instead of blending those that do");
  t.Real("--blend-power", &o.blend.power,
         "Blending sharpness p: weight (1/(angle penalty + 0.001 rad))^p")
      .Range(0, 64);
  t.Real("--feather", &o.blend.feather,
         "Pixels over which a projector fades out at its image border")
      .Range(0, 1000);
  t.Real("--res-weight", &o.blend.res_weight,
         "Blending: R x (1 - d_camera / d_projector) radians of penalty for a projector "
         "farther from a point than the camera (R/2 at twice as far)")
      .Range(0, 100);
  t.Real("--soft", &o.blend.soft,
         "Blending: soft occlusion width, relative (visibility 1 to 0 over depth*(1+bias..+soft))")
      .Range(0, 1, false, true);
  t.Flag("--no-fill", &o.no_fill,
         "Constant background where nothing is seen instead of filling from the surroundings");
  DeclareSeenOptions(t, o);
  t.Choice("--render-exposure", &o.render_exposure, kRenderExposures,
           "With exposure.tsv: record the render at its nearest projectors' exposure, or at the "
           "workspace's common one");
  t.Text("--size", &o.size, "Render size WxH (default: the camera's)")
      .Alternative("40x12")
      .Check([&o] {
        if (!o.size.empty()) ParseImageSize(o.size);
      });
  t.Flag("--explain", &o.explain,
         "Print the effects plan as JSON (with the reason for each effect) and render nothing")
      .Cosmetic();
  t.Flag("--provenance", &o.provenance,
         "Also write OUTDIR/provenance/NAME.png: which projector coloured each pixel (254 "
         "vertex colour, 255 background)");
  t.Flag("--exr", &o.exr, "Write float EXR frames (0..1) instead of 8-bit PNG");
  t.Choice("--gl", &o.gl, GlBackendTable(), "OpenGL backend");
  DeclareWorkOptions(t, o, "render poses", "in pose order", "Re-render frames that already exist");
  return t;
}

void PtmRenderOptions::Check() const {
  CheckDeclared(*this);
  if (!poses.empty() && at_images) throw UsageError("give --poses FILE or --at-images, not both");
  if (exclude_self && !at_images) throw UsageError("--exclude-self needs --at-images");
}

namespace {

using Clock = std::chrono::steady_clock;
double Ms(Clock::time_point a, Clock::time_point b) {
  return std::chrono::duration<double, std::milli>(b - a).count();
}

constexpr size_t kNoImage = static_cast<size_t>(-1);

struct RenderPose {
  std::string name;  // output file name (.png or .exr)
  Rigid3d w2c;
  size_t self = kNoImage;  // workspace image index with this pose (--at-images)
};

// The workspace's model, its images in processing order and their poses as projector candidates.
struct Scene {
  Reconstruction rec;
  std::vector<const ImageRecord*> images;  // ImagesByName
  std::vector<Rigid3d> candidates;         // images[i]->world_to_camera
};

// The projectors of every render pose, and what they say about the scene.
struct ProjectorPicks {
  std::vector<std::vector<Candidate>> per_pose;
  std::set<size_t> used;  // image indices any pose may use
  bool differs = false;   // a projector is not the pose it serves
  bool several = false;   // some pose has more than one admissible projector
};

std::string FrameName(const std::string& name, bool exr) {
  fs::path p(name);
  p.replace_extension(exr ? ".exr" : ".png");
  return p.string();
}

// The frame of --poses row i: named as in the file (images.txt), else 000000, 000001, ...
std::string PoseFrameName(const Trajectory& tr, size_t i, bool exr) {
  return FrameName(PoseName(tr, i), exr);
}

// OUTDIR/provenance/NAME.png: which projector coloured each pixel (--provenance).
fs::path ProvenanceMapPath(const PtmRenderOptions& o, const RenderPose& pose) {
  fs::path pp = fs::path(o.outdir) / "provenance" / pose.name;
  pp.replace_extension(".png");
  return pp;
}

Scene LoadScene(const Workspace& ws) {
  Scene s;
  s.rec = ReadColmapModel(ws.SparseDir().string());
  if (s.rec.images.empty()) throw Error(ws.SparseDir().string(), 0, "the model has no images");
  s.images = s.rec.ImagesByName();
  for (const auto* im : s.images) s.candidates.push_back(im->world_to_camera);
  return s;
}

// --poses FILE (names from the file, else 000000, 000001, ...) or the workspace's own poses.
std::vector<RenderPose> LoadRenderPoses(const PtmRenderOptions& o, const Scene& scene) {
  std::vector<RenderPose> poses;
  if (!o.poses.empty()) {
    Trajectory tr = ReadTrajectory(o.poses);
    for (size_t i = 0; i < tr.poses.size(); ++i)
      poses.push_back({PoseFrameName(tr, i, o.exr), tr.poses[i].pose.Inverse(), kNoImage});
  } else {
    for (size_t i = 0; i < scene.images.size(); ++i)
      poses.push_back(
          {FrameName(scene.images[i]->name, o.exr), scene.images[i]->world_to_camera, i});
  }
  if (o.lateral != 0 || o.yaw != 0)
    for (auto& p : poses) p.w2c = MovedAndTurned(p.w2c, o.lateral, o.yaw);
  return poses;
}

// The render camera (Reconstruction::RenderCamera), at --size if given.
Camera RenderCameraOf(const PtmRenderOptions& o, const Scene& scene) {
  if (o.size.empty()) return scene.rec.RenderCamera();
  const ImageSize size = ParseImageSize(o.size);
  return scene.rec.RenderCamera(size.width, size.height);
}

// Projectors for every pose (all poses: the plan must not depend on how the work is split).
ProjectorPicks PickProjectors(const PtmRenderOptions& o, const Scene& scene,
                              const std::vector<RenderPose>& poses) {
  ProjectorPicks picks;
  picks.per_pose.resize(poses.size());
  if (o.mode != PtmMode::kPtm) return picks;
  ViewSelectionOptions so = o.selection;
  so.k = static_cast<size_t>(o.projectors);
  for (size_t i = 0; i < poses.size(); ++i) {
    picks.per_pose[i] =
        SelectViews(poses[i].w2c, scene.candidates, so, o.exclude_self ? poses[i].self : kNoImage);
    for (const auto& c : picks.per_pose[i]) {
      picks.used.insert(c.index);
      const Rigid3d& p = scene.candidates[c.index];
      if ((p.t - poses[i].w2c.t).norm() > 0 || p.q.coeffs() != poses[i].w2c.q.coeffs())
        picks.differs = true;
    }
    picks.several |= picks.per_pose[i].size() > 1;
  }
  return picks;
}

SceneSurvey StartSurvey(const PtmRenderOptions& o, const Workspace& ws, const Scene& scene,
                        const ProjectorPicks& picks) {
  SceneSurvey s;
  s.ptm = o.mode == PtmMode::kPtm;
  s.projectors_requested = o.projectors;
  s.bias = o.bias;
  s.no_occlusion = o.no_occlusion;
  s.no_masks = o.no_masks;
  s.no_skybox = o.no_skybox;
  s.no_exposure = o.no_exposure;
  s.no_blend = o.no_blend;
  s.no_fill = o.no_fill;
  s.no_seen = o.no_seen;
  s.seen_surfaces = o.seen;
  s.sky_distance = o.sky_distance;
  if (s.ptm && !o.no_skybox) s.scene_far = SceneFarEnd(scene.rec);
  s.blend_weights = o.blend;
  s.projector_differs = picks.differs;
  s.several_admissible = picks.several;
  if (s.ptm && !o.no_masks) s.mask_example = FirstMaskedImage(ws, scene.images, picks.used);
  if (s.ptm && !o.no_exposure) s.exposure_example = FirstExposedImage(ws, scene.images, picks.used);
  if (s.ptm && !o.no_seen) s.seen_example = FirstSeenImage(ws, scene.images, picks.used);
  return s;
}

// Holes and coverage of the frames about to be rendered (a depth pass each).
void SurveyFrames(SceneSurvey& s, Renderer& renderer, const Camera& cam, const Scene& scene,
                  const std::vector<RenderPose>& poses, const ProjectorPicks& picks,
                  const std::vector<size_t>& frames) {
  for (size_t i : frames) {
    std::optional<View> first;
    if (!picks.per_pose[i].empty()) {
      const ImageRecord* pk = scene.images[picks.per_pose[i][0].index];
      first = View{scene.rec.cameras.at(pk->camera_id), pk->world_to_camera};
    }
    AddToSurvey(s, SurveyView(renderer, View{cam, poses[i].w2c}, first ? &*first : nullptr),
                poses[i].name);
  }
}

// Grey output when the source images are grey: decided over every image any pose may use (else
// the workspace's first image), so every split of the work decides alike.
bool GreySources(const Workspace& ws, const Scene& scene, const std::set<size_t>& used) {
  bool grey = true;
  for (size_t k : used)
    grey = grey && ReadImageSpec(ws.SourceImagePath(scene.images[k]->name).string()).channels == 1;
  if (used.empty())
    grey = ReadImageSpec(ws.SourceImagePath(scene.images[0]->name).string()).channels == 1;
  return grey;
}

// The files frame i is made from beyond the run's inputs: its projectors' images, masks, depth
// maps and densify's maps (absent ones count: a mask that appears makes the frame stale).
std::vector<fs::path> FrameInputs(const PtmRenderOptions& o, const Workspace& ws,
                                  const Scene& scene, const ProjectorPicks& picks, size_t i,
                                  const std::vector<fs::path>& extra) {
  std::vector<fs::path> in = extra;
  for (size_t j = 0; j < picks.per_pose[i].size(); ++j) {
    const std::string& name = scene.images[picks.per_pose[i][j].index]->name;
    in.push_back(ws.SourceImagePath(name));
    if (!o.no_masks) in.push_back(ws.MaskPath(name));
    if (!o.no_occlusion || !o.no_skybox) in.push_back(ws.DepthPath(name));
    if (o.mode == PtmMode::kPtm && !o.no_seen && j < size_t(o.seen.projectors)) {
      in.push_back(ws.StereoDepthPath(name));  // the projectors the seen surfaces search
      in.push_back(ws.StereoConfidencePath(name));
    }
  }
  return in;
}

std::vector<size_t> FramesToRender(const PtmRenderOptions& o, const Workspace& ws,
                                   const Scene& scene, const std::vector<RenderPose>& poses,
                                   const ProjectorPicks& picks, const std::vector<size_t>& chosen,
                                   const std::vector<fs::path>& extra, Ledger& ledger,
                                   PtmRenderReport& rep) {
  std::vector<size_t> todo;
  for (size_t i : chosen) {
    const std::vector<fs::path> in = FrameInputs(o, ws, scene, picks, i, extra);
    bool stale = !ledger.Stale(fs::path(o.outdir) / poses[i].name, in, o.force).empty();
    if (o.provenance)
      stale = !ledger.Stale(ProvenanceMapPath(o, poses[i]), in, o.force).empty() || stale;
    if (stale)
      todo.push_back(i);
    else
      ++rep.skipped;
  }
  return todo;
}

// The frame as written: grey (rounded) when the sources are grey; 0..1 float for EXR.
Image OutputImage(Image colour, bool grey, bool exr) {
  if (grey) {
    colour = ToGrey(colour);
    for (float& v : colour.data) v = std::nearbyint(v);
  }
  if (exr) {
    colour.bits = 32;
    for (float& v : colour.data) v /= 255.f;
  }
  return colour;
}

struct FrameJob {
  const PtmRenderOptions& o;
  const Workspace& ws;
  const Scene& scene;
  const Camera& cam;
  const std::vector<RenderPose>& poses;
  const ProjectorPicks& picks;
  Ledger& ledger;
  const std::vector<fs::path>& extra_inputs;  // a road's fragment files every frame depends on
};

std::vector<Projector> FrameProjectors(const FrameJob& job, const EffectsPlan& plan, size_t i,
                                       ProjectorSources& sources, PtmRenderReport& rep) {
  std::vector<size_t> indices;
  for (const auto& c : job.picks.per_pose[i]) indices.push_back(c.index);
  return GatherProjectors(sources, indices, plan, &rep.depth_ms);
}

// The exposure the render camera records at (ExposureNear), or the common one.
CameraExposure RenderExposureOf(const FrameJob& job, const EffectsPlan& plan,
                                const std::vector<Projector>& ps, size_t i) {
  if (!plan.exposure || job.o.render_exposure == RenderExposure::kCommon) return CameraExposure();
  return ExposureNear(ps, job.poses[i].w2c.Centre());
}

// Renders the frames, surveying each from its own render (its depth: holes, coverage) instead of
// a depth pass of its own. The plan starts as the survey without holes; the first frame with a
// hole turns the skybox and the fill on (PlanEffects) and is rendered again. Frames before it are
// unchanged by that, since the skybox only colours pixels with no surface.
void RenderFrames(const FrameJob& job, Renderer& renderer, const std::vector<size_t>& todo,
                  SceneSurvey& survey, EffectsPlan& plan, PtmRenderReport& rep) {
  const fs::path outdir(job.o.outdir);
  ProjectorSources sources(job.ws, job.scene.rec, job.scene.images, &renderer,
                           /*prefer_textures=*/true);
  const bool grey = GreySources(job.ws, job.scene, job.picks.used);
  AsyncImageWriter writer;
  Progress bar("ptmrender", todo.size(), job.o.quiet);
  for (size_t n = 0; n < todo.size(); ++n) {
    const size_t i = todo[n];
    const View view{job.cam, job.poses[i].w2c};
    Renderer::Frame f;
    bool surveyed = false;
    for (bool again = true; again;) {
      auto t0 = Clock::now();
      sources.Trim();  // between frames only: a frame's projectors hold references into it
      std::vector<Projector> ps = FrameProjectors(job, plan, i, sources, rep);
      if (n + 1 < todo.size()) {  // the next frame's files are read while this one renders
        std::vector<size_t> next;
        for (const auto& c : job.picks.per_pose[todo[n + 1]]) next.push_back(c.index);
        sources.Prefetch(next, plan.occlusion || plan.skybox, plan.masks, plan.SeenProjectors());
      }
      auto t1 = Clock::now();
      RenderStats stats;
      f = renderer.Render(view, ps, plan, &stats, /*with_depth=*/survey.ptm,
                          RenderExposureOf(job, plan, ps, i));
      auto t2 = Clock::now();
      rep.load_ms += Ms(t0, t1);
      rep.render_ms += Ms(t1, t2);
      rep.draw_ms += stats.draw_ms;
      rep.shade_ms += stats.shade_ms;
      rep.readback_ms += stats.readback_ms;
      rep.fill_ms += stats.fill_ms;
      again = false;
      if (survey.ptm && !surveyed) {
        AddToSurvey(survey, CoverageOf(f.depth, view, ps.empty() ? nullptr : &ps[0].view),
                    job.poses[i].name);
        surveyed = true;
        const EffectsPlan now = PlanEffects(survey);
        again = now.skybox != plan.skybox || now.fill != plan.fill;
        plan = now;
        rep.survey_ms += Ms(t2, Clock::now());
      }
    }
    Image colour = OutputImage(std::move(f.colour), grey, job.o.exr);
    auto t3 = Clock::now();
    // Frames are photo-like: the fast PNG settings encode them 3x faster than the default
    // (the writer thread was the frame loop's limit) and smaller; provenance maps are flat.
    const std::vector<fs::path> in =
        FrameInputs(job.o, job.ws, job.scene, job.picks, i, job.extra_inputs);
    writer.Push((outdir / job.poses[i].name).string(), std::move(colour), PngCompression::kFast,
                [&ledger = job.ledger, in](const std::string& p) { ledger.Done(p, in); });
    if (job.o.provenance)
      writer.Push(ProvenanceMapPath(job.o, job.poses[i]).string(), std::move(f.source),
                  PngCompression::kFastFlat,
                  [&ledger = job.ledger, in](const std::string& p) { ledger.Done(p, in); });
    rep.write_ms += Ms(t3, Clock::now());
    ++rep.rendered;
    bar.Step();
  }
  auto t_finish = Clock::now();
  writer.Finish();
  rep.write_ms += Ms(t_finish, Clock::now());
}

nlohmann::json PlanJson(const Camera& cam, size_t frames, const std::string& gl,
                        const SceneSurvey& survey, const EffectsPlan& plan) {
  nlohmann::json j;
  j["frames"] = frames;
  j["render_size"] = {cam.width, cam.height};
  j["gl"] = gl;
  j["effects"] = ExplainEffects(survey, plan);
  j["shader_defines"] = plan.Defines();
  return j;
}

Mesh LoadMesh(const Workspace& ws, bool ptm) {
  Mesh mesh = ReadMesh(ws.MeshPath().string());
  if (mesh.faces.empty()) throw Error(ws.MeshPath().string(), 0, "the mesh has no triangles");
  if (!ptm && !mesh.has_colors())
    throw Error(ws.MeshPath().string(), 0, "vertex mode needs vertex colours (the mesh has none)");
  return mesh;
}

// ---- a road (ROAD/Graph.txt): fragments streamed by the graph --------------------------------

// A frame of a road render: the fragment the camera is in (its projectors and plan), the pose.
struct RoadFrameJob {
  size_t home = 0;
  RenderPose pose;
  std::string image;  // the recorded image at this pose ("" for --poses)
};

// The road's recorded frames in order: each fragment's own images, fragments in Graph.txt's
// order; or the poses of --poses, each in the fragment of its nearest recorded image, walking
// the graph (a pose whose nearest fragment is neither the current one nor a neighbour leaves
// the graph: an error).
std::vector<RoadFrameJob> RoadFrames(const PtmRenderOptions& o, const Road& road) {
  const RoadLocator where(road);
  std::vector<RoadFrameJob> frames;
  for (const RoadRecordedFrame& f : where.frames())
    frames.push_back(
        {f.home, {FrameName(f.image->name, o.exr), f.image->world_to_camera}, f.image->name});
  if (o.poses.empty()) {
    if (o.lateral != 0 || o.yaw != 0)
      for (auto& fr : frames) fr.pose.w2c = MovedAndTurned(fr.pose.w2c, o.lateral, o.yaw);
    return frames;
  }
  const Trajectory tr = ReadTrajectory(o.poses);
  std::vector<RoadFrameJob> out;
  std::optional<size_t> home;
  for (size_t i = 0; i < tr.poses.size(); ++i) {
    const Rigid3d w2c = tr.poses[i].pose.Inverse();
    home = where.Locate(w2c.Centre(), home, o.poses + ": pose " + std::to_string(i + 1));
    out.push_back(
        {*home, {PoseFrameName(tr, i, o.exr), MovedAndTurned(w2c, o.lateral, o.yaw)}, ""});
  }
  return out;
}

// The files a road frame depends on beyond its projectors: the home fragment's model and record,
// and every resident fragment's mesh and record.
std::vector<fs::path> ResidentInputs(const PtmRenderOptions& o, const Road& road, size_t home) {
  const Workspace ws(road.fragments()[home].dir);
  std::vector<fs::path> in = ws.SparseModelFiles();
  if (!o.no_exposure) in.push_back(ws.ExposurePath());
  for (fs::path& p : road.ResidentFiles(home)) in.push_back(std::move(p));
  return in;
}

// One run of consecutive frames in the same fragment, rendered like a workspace of its own with
// the resident fragments' mesh.
struct RoadGroup {
  size_t home = 0;
  std::vector<size_t> frames;  // indices into the road's frames
};

std::vector<RoadGroup> GroupByHome(const std::vector<RoadFrameJob>& frames,
                                   const std::vector<size_t>& chosen) {
  std::vector<RoadGroup> groups;
  for (size_t i : chosen) {
    if (groups.empty() || groups.back().home != frames[i].home)
      groups.push_back({frames[i].home, {}});
    groups.back().frames.push_back(i);
  }
  return groups;
}

struct RoadRun {
  const PtmRenderOptions& o;
  const Road& road;
  const std::vector<RoadFrameJob>& frames;
  Ledger& ledger;
  std::unique_ptr<GlContext>& ctx;
  RoadMeshes& meshes;
  nlohmann::json plans = nlohmann::json::object();
  nlohmann::json explained = nlohmann::json::array();  // --explain: one plan per group
};

// Renders one group: the home fragment's scene, projectors and plan, the resident mesh.
void RenderRoadGroup(RoadRun& run, const RoadGroup& g, const std::vector<size_t>& next_resident,
                     PtmRenderReport& rep) {
  const PtmRenderOptions& o = run.o;
  const Workspace ws(run.road.fragments()[g.home].dir);
  const Scene scene = LoadScene(ws);
  std::vector<RenderPose> poses;
  for (size_t i : g.frames) {
    RenderPose p = run.frames[i].pose;
    for (size_t k = 0; k < scene.images.size() && !run.frames[i].image.empty(); ++k)
      if (scene.images[k]->name == run.frames[i].image) p.self = k;
    poses.push_back(p);
  }
  std::vector<size_t> all(poses.size());
  for (size_t i = 0; i < all.size(); ++i) all[i] = i;
  const Camera cam = RenderCameraOf(o, scene);
  const ProjectorPicks picks = PickProjectors(o, scene, poses);
  SceneSurvey survey = StartSurvey(o, ws, scene, picks);
  const std::vector<fs::path> extra = ResidentInputs(o, run.road, g.home);
  PtmRenderReport part;
  const std::vector<size_t> todo =
      o.explain ? all : FramesToRender(o, ws, scene, poses, picks, all, extra, run.ledger, part);
  rep.skipped += part.skipped;
  const std::vector<size_t> resident = run.road.Resident(g.home);
  if (todo.empty()) return;
  const Mesh mesh = run.meshes.Union(resident, next_resident);
  const fs::path home_dir = run.road.fragments()[g.home].dir;
  if (mesh.faces.empty())
    throw Error(home_dir.string(), 0, "no triangles in this fragment or its neighbours");
  if (!survey.ptm && !mesh.has_colors())
    throw Error(home_dir.string(), 0,
                "vertex mode needs vertex colours (a resident mesh has none)");
  if (!run.ctx) {  // created on the first group with work: an up-to-date road needs no GL
    run.ctx = GlContext::Create(o.gl);
    rep.gl = run.ctx->Describe();
  }
  Renderer renderer(mesh);
  const std::string& id = run.road.fragments()[g.home].id;
  if (o.explain) {  // the group's plan, as --explain prints it for a workspace
    SurveyFrames(survey, renderer, cam, scene, poses, picks, all);
    nlohmann::json j = PlanJson(cam, poses.size(), rep.gl, survey, PlanEffects(survey));
    j["fragment"] = id;
    j["first_frame"] = poses.front().name;
    run.explained.push_back(std::move(j));
    return;
  }
  EffectsPlan plan = PlanEffects(survey);
  RenderFrames(FrameJob{o, ws, scene, cam, poses, picks, run.ledger, extra}, renderer, todo, survey,
               plan, rep);
  run.plans[id] = PlanJson(cam, poses.size(), rep.gl, survey, plan)["effects"];
}

PtmRenderReport RunRoadRender(const PtmRenderOptions& o, std::ostream& out) {
  const Road road(o.workspace);
  const std::vector<RoadFrameJob> frames = RoadFrames(o, road);
  // Shards are contiguous runs of the road's frames: each reads a few fragments, not all.
  const std::vector<size_t> chosen = o.Select().ApplyBlocks(frames.size());
  PtmRenderReport rep;
  rep.frames = chosen.size();
  std::vector<fs::path> inputs{road.GraphPath()};
  if (!o.poses.empty()) inputs.push_back(o.poses);
  PtmRenderOptions resolved = o;
  const OptionTable table = DeclareOptions(resolved);
  Ledger ledger(o.outdir, o.ProvenanceName("ptmrender"), table, inputs, road.root());
  if (!o.explain) {
    RemoveStaleTemporaries(o.outdir);
    if (o.provenance) RemoveStaleTemporaries(fs::path(o.outdir) / "provenance");
  }
  std::unique_ptr<GlContext> ctx;
  RoadMeshes meshes(road);
  RoadRun run{o, road, frames, ledger, ctx, meshes};
  const std::vector<RoadGroup> groups = GroupByHome(frames, chosen);
  auto t0 = Clock::now();
  for (size_t n = 0; n < groups.size(); ++n) {
    const std::vector<size_t> next =
        n + 1 < groups.size() ? road.Resident(groups[n + 1].home) : std::vector<size_t>{};
    RenderRoadGroup(run, groups[n], next, rep);
    // The group's meshes, images and renderer are gone: hand the freed heap back, so a long road
    // does not grow the process by the fragmentation the reader threads leave.
    malloc_trim(0);
  }
  rep.depth_ms += rep.survey_ms;
  rep.frames_ms = Ms(t0, Clock::now());
  rep.why = ledger.Summary();
  if (o.explain) {
    out << nlohmann::json{{"road", road.root().string()}, {"groups", run.explained}}.dump(2)
        << "\n";
    return rep;
  }
  if (rep.rendered > 0) ledger.Write({{"plans", run.plans}, {"gl_used", rep.gl}});
  return rep;
}
}  // namespace

PtmRenderReport RunPtmRender(const PtmRenderOptions& o, std::ostream& out) {
  o.Check();
  if (Road::IsRoad(o.workspace)) return RunRoadRender(o, out);
  Workspace ws(o.workspace);
  ws.Require("ptmrender", {WsItem::kSparse, WsItem::kMesh});
  const Scene scene = LoadScene(ws);
  const std::vector<RenderPose> poses = LoadRenderPoses(o, scene);
  const std::vector<size_t> chosen = o.Select().Apply(poses.size());
  const Camera cam = RenderCameraOf(o, scene);
  const ProjectorPicks picks = PickProjectors(o, scene, poses);
  SceneSurvey survey = StartSurvey(o, ws, scene, picks);

  PtmRenderReport rep;
  rep.frames = chosen.size();
  std::vector<fs::path> inputs = ws.SparseModelFiles();
  inputs.push_back(ws.MeshPath());
  if (!o.poses.empty()) inputs.push_back(o.poses);
  if (!o.no_exposure) inputs.push_back(ws.ExposurePath());
  PtmRenderOptions resolved = o;
  const OptionTable table = DeclareOptions(resolved);
  Ledger ledger(o.outdir, o.ProvenanceName("ptmrender"), table, inputs, ws.root());
  const std::vector<size_t> todo =
      o.explain ? chosen : FramesToRender(o, ws, scene, poses, picks, chosen, {}, ledger, rep);
  rep.why = ledger.Summary();
  if (!o.explain) {  // a killed run's leftovers go, even when every frame is up to date
    RemoveStaleTemporaries(o.outdir);
    if (o.provenance) RemoveStaleTemporaries(fs::path(o.outdir) / "provenance");
  }
  if (todo.empty() && !o.explain) return rep;

  const Mesh mesh = LoadMesh(ws, survey.ptm);
  auto ctx = GlContext::Create(o.gl);
  rep.gl = ctx->Describe();
  Renderer renderer(mesh);
  auto t_plan = Clock::now();
  if (o.explain) {
    SurveyFrames(survey, renderer, cam, scene, poses, picks, chosen);
    out << PlanJson(cam, chosen.size(), rep.gl, survey, PlanEffects(survey)).dump(2) << "\n";
    return rep;
  }
  EffectsPlan plan = PlanEffects(survey);
  const std::vector<fs::path> no_extra;
  RenderFrames(FrameJob{o, ws, scene, cam, poses, picks, ledger, no_extra}, renderer, todo, survey,
               plan, rep);
  rep.depth_ms += rep.survey_ms;
  rep.frames_ms = Ms(t_plan, Clock::now());
  const nlohmann::json plan_json = PlanJson(cam, chosen.size(), rep.gl, survey, plan);
  ledger.Write({{"plan", plan_json["effects"]}, {"gl_used", rep.gl}});
  return rep;
}

}  // namespace mvtm
