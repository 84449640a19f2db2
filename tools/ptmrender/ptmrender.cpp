#include "ptmrender.h"

#include <chrono>
#include <cmath>
#include <condition_variable>
#include <cstdio>
#include <deque>
#include <limits>
#include <map>
#include <mutex>
#include <set>
#include <nlohmann/json.hpp>
#include <ostream>
#include <thread>

#include "base/atomic_file.h"
#include "cli/progress.h"
#include "base/error.h"
#include "cli/selection.h"
#include "base/text.h"
#include "image/mask.h"
#include "io/colmap_model.h"
#include "io/trajectory.h"
#include "render/context.h"
#include "render/projector_sources.h"
#include "workspace/workspace.h"

namespace mvtm {

void PtmRenderOptions::Check() const {
  if (!poses.empty() && at_images) throw UsageError("give --poses FILE or --at-images, not both");
  if (exclude_self && !at_images) throw UsageError("--exclude-self needs --at-images");
  CheckChoice(mode, kPtmModes, "--mode");
  if (projectors < 1 || projectors > 16) throw UsageError("--projectors: must be 1..16");
  if (!(bias >= 0 && bias < 1)) throw UsageError("--bias: must be in [0, 1)");
  if (!std::isfinite(lateral) || !std::isfinite(yaw)) throw UsageError("--lateral/--yaw must be finite");
  CheckWork();
  if (!(selection.ahead_weight >= 0 && std::isfinite(selection.ahead_weight)))
    throw UsageError("--ahead-weight: must be a finite number >= 0");
  if (!(selection.max_heading_deg > 0 && selection.max_heading_deg <= 180))
    throw UsageError("--max-heading: must be in (0, 180]");
  ParseGlBackend(gl);
}

namespace {

using Clock = std::chrono::steady_clock;
double Ms(Clock::time_point a, Clock::time_point b) { return std::chrono::duration<double, std::milli>(b - a).count(); }

struct RenderPose {
  std::string name;  // output file name (.png)
  Rigid3d w2c;
  size_t self = static_cast<size_t>(-1);  // workspace image index with this pose (--at-images)
};

std::string PngName(const std::string& name, bool exr) {
  fs::path p(name);
  p.replace_extension(exr ? ".exr" : ".png");
  return p.string();
}

// Lane change and turn, about the camera's own axes: left = −x, up = −y (level cameras: world up).
Rigid3d Offset(const Rigid3d& w2c, double lateral_left, double yaw_left_deg) {
  Rigid3d c2w = w2c.Inverse();
  Eigen::Matrix3d R = c2w.R();
  c2w.t -= lateral_left * R.col(0);
  Eigen::Vector3d up = -R.col(1);
  c2w.q = Eigen::Quaterniond(Eigen::AngleAxisd(yaw_left_deg * M_PI / 180.0, up)) * c2w.q;
  c2w.q.normalize();
  return c2w.Inverse();
}

std::string ShortDouble(double v) {
  char b[32];
  std::snprintf(b, sizeof b, "%g", v);
  return b;
}

// Writes finished frames on a second thread so that PNG encoding overlaps rendering.
class AsyncWriter {
 public:
  AsyncWriter() : thread_([this] { Loop(); }) {}
  ~AsyncWriter() { Finish(); }
  void Push(std::string path, Image img) {
    std::unique_lock<std::mutex> l(mu_);
    cv_.wait(l, [&] { return queue_.size() < 4 || !error_.empty(); });
    if (!error_.empty()) throw Error(error_);
    queue_.emplace_back(std::move(path), std::move(img));
    cv_.notify_all();
  }
  void Finish() {
    {
      std::lock_guard<std::mutex> l(mu_);
      done_ = true;
      cv_.notify_all();
    }
    if (thread_.joinable()) thread_.join();
    if (!error_.empty() && !reported_) {
      reported_ = true;
      throw Error(error_);
    }
  }

 private:
  void Loop() {
    for (;;) {
      std::pair<std::string, Image> job;
      {
        std::unique_lock<std::mutex> l(mu_);
        cv_.wait(l, [&] { return !queue_.empty() || done_; });
        if (queue_.empty()) return;
        job = std::move(queue_.front());
        queue_.pop_front();
        cv_.notify_all();
      }
      try {
        WriteImage(job.first, job.second);
      } catch (const std::exception& e) {
        std::lock_guard<std::mutex> l(mu_);
        error_ = e.what();
        queue_.clear();
        cv_.notify_all();
        return;
      }
    }
  }
  std::mutex mu_;
  std::condition_variable cv_;
  std::deque<std::pair<std::string, Image>> queue_;
  bool done_ = false, reported_ = false;
  std::string error_;
  std::thread thread_;
};

}  // namespace

PtmRenderReport RunPtmRender(const PtmRenderOptions& o, std::ostream& out) {
  o.Check();
  Workspace ws(o.workspace);
  ws.Require("ptmrender", {WsItem::kSparse, WsItem::kMesh});
  Reconstruction rec = ReadColmapModel(ws.SparseDir().string());
  if (rec.images.empty()) throw Error(ws.SparseDir().string(), 0, "the model has no images");
  auto images = rec.ImagesByName();
  std::vector<Rigid3d> cand;
  for (const auto* im : images) cand.push_back(im->world_to_camera);
  const bool ptm = o.mode == "ptm";

  // Render poses.
  std::vector<RenderPose> poses;
  if (!o.poses.empty()) {
    Trajectory tr = ReadTrajectory(o.poses);
    char buf[32];
    for (size_t i = 0; i < tr.poses.size(); ++i) {
      std::snprintf(buf, sizeof buf, "%06zu", i);
      std::string name = i < tr.names.size() ? tr.names[i] : buf;
      poses.push_back({PngName(name, o.exr), tr.poses[i].pose.Inverse(), static_cast<size_t>(-1)});
    }
  } else {
    for (size_t i = 0; i < images.size(); ++i)
      poses.push_back({PngName(images[i]->name, o.exr), images[i]->world_to_camera, i});
  }
  if (o.lateral != 0 || o.yaw != 0)
    for (auto& p : poses) p.w2c = Offset(p.w2c, o.lateral, o.yaw);
  Selection sel = o.Select();
  std::vector<size_t> chosen = sel.Apply(poses.size());

  // The render camera: the workspace's (first) camera, at --size if given.
  Camera cam = rec.cameras.begin()->second;
  cam.RequireUndistorted();
  if (!o.size.empty()) {
    const ImageSize size = ParseImageSize(o.size);
    cam = cam.Scaled(size.width, size.height);
  }

  // Projectors per pose (all poses: the plan must not depend on how the work is split).
  ViewSelectionOptions so = o.selection;
  so.k = static_cast<size_t>(o.projectors);
  std::vector<std::vector<Candidate>> picks(poses.size());
  bool any_differs = false, any_several = false;
  std::set<size_t> used;
  if (ptm) {
    for (size_t i = 0; i < poses.size(); ++i) {
      picks[i] = SelectViews(poses[i].w2c, cand, so, o.exclude_self ? poses[i].self : static_cast<size_t>(-1));
      for (const auto& c : picks[i]) {
        used.insert(c.index);
        if ((cand[c.index].t - poses[i].w2c.t).norm() > 0 || cand[c.index].q.coeffs() != poses[i].w2c.q.coeffs())
          any_differs = true;
      }
      any_several |= picks[i].size() > 1;
    }
  }
  bool any_mask = false;
  std::string mask_example;
  if (ptm && !o.no_masks)
    for (size_t i : used) {
      fs::path mp = ws.MaskPath(images[i]->name);
      if (fs::exists(mp) && CountSet(ReadMask(mp.string())) > 0) {
        any_mask = true;
        mask_example = mp.filename().string();
        break;
      }
    }

  PtmRenderReport rep;
  rep.frames = chosen.size();
  fs::path outdir(o.outdir);
  std::vector<fs::path> inputs = {ws.MeshPath()};
  std::vector<size_t> todo;
  for (size_t i : chosen) {
    if (!o.explain && !o.force && IsUpToDate(outdir / poses[i].name, inputs)) {
      ++rep.skipped;
      continue;
    }
    todo.push_back(i);
  }
  if (todo.empty() && !o.explain) return rep;

  Mesh mesh = ReadMesh(ws.MeshPath().string());
  if (mesh.faces.empty()) throw Error(ws.MeshPath().string(), 0, "the mesh has no triangles");
  if (!ptm && !mesh.has_colors()) throw Error(ws.MeshPath().string(), 0, "vertex mode needs vertex colours (the mesh has none)");
  auto ctx = GlContext::Create(ParseGlBackend(o.gl));
  rep.gl = ctx->Describe();
  Renderer renderer(mesh);

  // Holes: does the render see no surface somewhere? (A depth pass per frame to render.)
  auto t_plan = Clock::now();
  size_t frames_with_holes = 0;
  double min_coverage = 1.0;
  std::string hole_example;
  for (size_t i : (o.explain ? chosen : todo)) {
    View v{cam, poses[i].w2c};
    Image d = renderer.RenderDepth(v);
    size_t holes = 0, surf = 0, covered = 0;
    const Eigen::Matrix3d Rt = v.world_to_camera.R().transpose();
    const Eigen::Vector3d C = v.world_to_camera.Centre();
    // Every pixel: a frame with a single hole pixel must get the same plan in every split.
    for (int y = 0; y < d.height; ++y)
      for (int x = 0; x < d.width; ++x) {
        float z = d.at(x, y);
        if (!std::isfinite(z)) {
          ++holes;
          continue;
        }
        ++surf;
        if (picks[i].empty()) continue;
        const auto& pk = images[picks[i][0].index];
        Eigen::Vector3d X = Rt * cam.Unproject({x + 0.5, y + 0.5}, z) + C;
        Eigen::Vector3d xp = pk->world_to_camera * X;
        const Camera& pc = rec.cameras.at(pk->camera_id);
        if (xp.z() <= 0) continue;
        Eigen::Vector2d uv = pc.Project(xp);
        covered += uv.x() >= 0 && uv.y() >= 0 && uv.x() < double(pc.width) && uv.y() < double(pc.height);
      }
    if (holes) {
      ++frames_with_holes;
      if (hole_example.empty()) hole_example = poses[i].name;
    }
    if (surf) min_coverage = std::min(min_coverage, double(covered) / double(surf));
  }
  rep.depth_ms += Ms(t_plan, Clock::now());

  EffectsPlan plan;
  plan.ptm = ptm;
  plan.bias = o.bias;
  plan.projectors = ptm && any_several ? o.projectors : 1;
  plan.occlusion = ptm && !o.no_occlusion && any_differs;
  plan.masks = ptm && any_mask;
  plan.skybox = ptm && !o.no_skybox && frames_with_holes > 0;

  auto reason = [&](bool on, const std::string& why_on, const std::string& why_off) {
    return nlohmann::json{{"on", on}, {"reason", on ? why_on : why_off}};
  };
  char cov[64];
  std::snprintf(cov, sizeof cov, "%.1f %%", 100 * min_coverage);
  nlohmann::json j;
  j["frames"] = chosen.size();
  j["render_size"] = {cam.width, cam.height};
  j["gl"] = rep.gl;
  j["effects"] = {
      {"reverse_projection_rejection", reason(ptm, "always on in PTM: cheap and always correct", "vertex-colour mode")},
      {"clip_test", reason(ptm, "always on in PTM: cheap and always correct", "vertex-colour mode")},
      {"occlusion", reason(plan.occlusion,
                           "projectors differ from the render poses, so the mesh can hide points from them; relative bias " + ShortDouble(o.bias),
                           !ptm ? "vertex-colour mode" : o.no_occlusion ? "turned off by --no-occlusion" : "every projector is the render pose itself")},
      {"several_projectors", reason(plan.projectors > 1,
                                    "up to " + std::to_string(plan.projectors) + " projectors per pixel, nearest first, then vertex colours; the first projector covers as little as " + std::string(cov) + " of a view",
                                    !ptm ? "vertex-colour mode" : o.projectors == 1 ? "--projectors 1 (vertex colours where it does not reach)" : "no frame has more than one admissible projector")},
      {"vertex_colour_fallback", reason(true, ptm ? "where no projector reaches" : "vertex-colour mode", "")},
      {"masks", reason(plan.masks, "selected projector " + mask_example + " has masked pixels",
                       !ptm ? "vertex-colour mode" : o.no_masks ? "turned off by --no-masks" : "no selected projector has a non-empty mask")},
      {"skybox", reason(plan.skybox,
                        std::to_string(frames_with_holes) + " of " + std::to_string(o.explain ? chosen.size() : todo.size()) + " frames see no surface somewhere (e.g. " + hole_example + ")",
                        !ptm ? "vertex-colour mode" : o.no_skybox ? "turned off by --no-skybox" : "every pixel of every frame sees the mesh")}};
  j["shader_defines"] = plan.Defines();
  if (o.explain) {
    out << j.dump(2) << "\n";
    return rep;
  }

  // Render.
  ProjectorSources sources(ws, rec, images, &renderer, /*prefer_textures=*/true);
  bool grey_sources = true;
  // Grey output when the source images are grey: decided over every image any pose may use
  // (else the workspace's first image), so every split of the work decides alike.
  for (size_t k : used) grey_sources = grey_sources && ReadImageSpec(ws.SourceImagePath(images[k]->name).string()).channels == 1;
  if (used.empty()) grey_sources = ReadImageSpec(ws.SourceImagePath(images[0]->name).string()).channels == 1;
  RemoveStaleTemporaries(outdir);
  if (o.provenance) RemoveStaleTemporaries(outdir / "provenance");
  AsyncWriter writer;
  Progress bar("ptmrender", todo.size(), o.quiet);
  for (size_t i : todo) {
    auto t0 = Clock::now();
    sources.Trim();  // between frames only: a frame's projectors hold references into it
    std::vector<Projector> ps;
    for (const auto& c : picks[i]) {
      Projector p;
      p.view = sources.ViewOf(c.index);
      p.image = &sources.ImageOf(c.index);
      p.key = static_cast<int64_t>(c.index);
      if (plan.occlusion || plan.skybox) {
        auto td = Clock::now();
        p.depth = &sources.DepthOf(c.index);
        rep.depth_ms += Ms(td, Clock::now());
      }
      if (plan.masks) p.mask = sources.MaskOf(c.index);
      ps.push_back(p);
    }
    auto t1 = Clock::now();
    Renderer::Frame f = renderer.Render(View{cam, poses[i].w2c}, ps, plan);
    auto t2 = Clock::now();
    rep.load_ms += Ms(t0, t1);
    rep.render_ms += Ms(t1, t2);
    Image colour = grey_sources ? ToGrey(f.colour) : std::move(f.colour);
    if (grey_sources)
      for (float& v : colour.data) v = std::nearbyint(v);
    if (o.exr) {
      colour.bits = 32;
      for (float& v : colour.data) v /= 255.f;
    }
    writer.Push((outdir / poses[i].name).string(), std::move(colour));
    if (o.provenance) {
      fs::path pp = outdir / "provenance" / poses[i].name;
      pp.replace_extension(".png");
      writer.Push(pp.string(), std::move(f.source));
    }
    ++rep.rendered;
    bar.Step();
  }
  writer.Finish();
  nlohmann::json opts = {{"poses", o.poses.empty() ? "workspace images" : o.poses}, {"exclude_self", o.exclude_self},
                         {"lateral", o.lateral}, {"yaw", o.yaw}, {"mode", o.mode}, {"projectors", o.projectors},
                         {"bias", o.bias}, {"frames", o.frames}, {"shard", o.shard}, {"outdir", o.outdir},
                         {"plan", j["effects"]}, {"gl", rep.gl}};
  ws.WriteProvenance(o.ProvenanceName("ptmrender"), opts, inputs);
  return rep;
}

}  // namespace mvtm
