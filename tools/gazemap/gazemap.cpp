#include "gazemap.h"

#include <charconv>
#include <cmath>
#include <cstdio>
#include <map>
#include <memory>
#include <nlohmann/json.hpp>
#include <sstream>

#include "base/atomic_file.h"
#include "base/error.h"
#include "base/text.h"
#include "cli/work.h"
#include "drive/ground.h"
#include "gaze/gaze_tsv.h"
#include "gaze/ivt.h"
#include "gaze/mapping.h"
#include "gaze/pictures.h"
#include "io/colmap_model.h"
#include "io/mesh_io.h"
#include "io/trajectory.h"
#include "workspace/workspace.h"

namespace mvtm {

namespace {

// "WxH" with decimals allowed, both > 0.
Eigen::Vector2d ParseWH(const std::string& text, const std::string& option) {
  const auto f = SplitChar(text, 'x');
  if (f.size() != 2) throw UsageError(option + ": expected WxH, got '" + text + "'");
  const Eigen::Vector2d v(ParseDoubleArg(f[0], option), ParseDoubleArg(f[1], option));
  if (!(v.x() > 0 && v.y() > 0)) throw UsageError(option + ": W and H must be > 0");
  return v;
}

std::string Fmt(const char* format, double v) {
  char buf[64];
  std::snprintf(buf, sizeof buf, format, v);
  return buf;
}

ScreenGeometry MakeScreen(const GazemapOptions& o, const Camera& render) {
  ScreenGeometry s;
  const Eigen::Vector2d px = o.screen.empty() ? Eigen::Vector2d(render.width, render.height)
                                              : ParseWH(o.screen, "--screen");
  s.width_px = px.x();
  s.height_px = px.y();
  if (!o.screen_mm.empty()) {
    const Eigen::Vector2d mm = ParseWH(o.screen_mm, "--screen-mm");
    s.width_mm = mm.x();
    s.height_mm = mm.y();
    s.distance_mm = o.distance;
  } else {
    s.px_per_degree = o.px_per_degree;
  }
  return s;
}

struct Frames {
  std::vector<Rigid3d> w2c;
  std::unique_ptr<FrameClock> clock;
};

Frames LoadFrames(const GazemapOptions& o) {
  const TrajectoryFormat format = DetectTrajectoryFormat(o.frames);
  const Trajectory tr = ReadTrajectory(o.frames, format);
  if (tr.poses.empty()) throw Error(o.frames, 0, "no poses");
  if (format != TrajectoryFormat::kTum && o.frame_rate <= 0)
    throw UsageError(o.frames +
                     ": a KITTI or COLMAP trajectory has no display times: give --frame-rate HZ");
  Frames f;
  std::vector<double> times;
  for (size_t i = 0; i < tr.poses.size(); ++i) {
    const StampedPose& p = tr.poses[i];
    const double t = o.frame_rate > 0 ? static_cast<double>(i) / o.frame_rate : p.time;
    if (i && !(t > times.back()))
      throw Error(o.frames, p.line,
                  "time " + FormatShort(t) + " is not after the previous frame's " +
                      FormatShort(times.back()) + ": display times must increase");
    times.push_back(t);
    f.w2c.push_back(p.pose.Inverse());
  }
  f.clock = std::make_unique<FrameClock>(times);
  return f;
}

void CheckGazeTimes(const GazeTrace& g, const FrameClock& clock, const GazemapOptions& o) {
  for (const GazeSample& s : g.samples)
    if (!clock.FrameAt(s.time))
      throw Error(o.gaze, s.line,
                  "time " + FormatShort(s.time) + " is outside the frames' display times [" +
                      FormatShort(clock.begin()) + ", " + FormatShort(clock.end()) + ") of " +
                      o.frames + " (same clock and unit, seconds?)");
}

std::vector<SourceView> LoadViews(const Reconstruction& rec) {
  std::vector<SourceView> views;
  for (const ImageRecord* im : rec.ImagesByName()) {
    const Camera& cam = rec.cameras.at(im->camera_id);
    cam.RequireUndistorted();
    views.push_back({im->name, cam,
                     Rigid3d(NormalizedQuaternion(im->world_to_camera.q), im->world_to_camera.t)});
  }
  return views;
}

// Depth maps and label images read on first use.
class MapCache {
 public:
  MapCache(const Workspace& ws, const std::vector<SourceView>& views) : ws_(ws), views_(views) {}
  const Image* Depth(size_t i) { return Get(depth_, i, ws_.DepthPath(views_[i].name), true); }
  const Image* Labels(size_t i) { return Get(labels_, i, ws_.LabelPath(views_[i].name), false); }

 private:
  const Image* Get(std::map<size_t, std::unique_ptr<Image>>& m, size_t i, const fs::path& p,
                   bool depth) {
    auto it = m.find(i);
    if (it != m.end()) return it->second.get();
    std::unique_ptr<Image> img;
    if (fs::exists(p)) {
      img = std::make_unique<Image>(depth ? ReadFloatMap(p.string()) : ReadImage(p.string()));
      RequireImageSize(*img, p.string(), views_[i].camera.width, views_[i].camera.height);
    }
    return m.emplace(i, std::move(img)).first->second.get();
  }
  const Workspace& ws_;
  const std::vector<SourceView>& views_;
  std::map<size_t, std::unique_ptr<Image>> depth_, labels_;
};

struct Mapped {
  Fixation f;
  size_t frame = 0;
  bool hit = false;
  Eigen::Vector3d X = Eigen::Vector3d::Constant(NAN);
  double distance = NAN;
  std::vector<SourceHit> sources;
  std::string aoi;
};

std::vector<Mapped> MapFixations(const IvtResult& ivt, const Frames& frames, const Camera& render,
                                 const ScreenGeometry& screen, const MeshRaycaster& mesh,
                                 const std::vector<SourceView>& views, MapCache& cache,
                                 const GazemapOptions& o) {
  std::vector<Mapped> out;
  const VisibilityOptions vo{o.depth_tolerance, 1e-3};
  const DepthLookup depth = [&](size_t i) {
    return o.visibility == "depth" ? cache.Depth(i) : nullptr;
  };
  for (const Fixation& f : ivt.fixations) {
    Mapped m;
    m.f = f;
    m.frame = *frames.clock->FrameAt(0.5 * (f.start + f.end));
    const Rigid3d& pose = frames.w2c[m.frame];
    const WorldRay ray = ScreenRay(render, pose, screen.width_px, screen.height_px, f.x, f.y);
    if (const auto hit = mesh.Closest(ray.origin, ray.direction)) {
      m.hit = true;
      m.X = hit->point;
      m.distance = (hit->point - ray.origin).norm();
      m.sources = SourcesOf(m.X, hit->normal, ray.origin, views, mesh, depth, vo);
    }
    out.push_back(std::move(m));
  }
  return out;
}

// The AOI of each fixation: its box, or the label at its pixel in the nearest source photo that
// has a label image.
std::string AssignAois(std::vector<Mapped>& mapped, const std::vector<AoiBox>& boxes,
                       MapCache& cache, const Workspace& ws, const GazemapOptions& o) {
  const bool labels = boxes.empty() && fs::is_directory(ws.LabelsDir());
  for (Mapped& m : mapped) {
    if (!m.hit) {
      m.aoi = "no-surface";
      continue;
    }
    if (!boxes.empty()) {
      m.aoi = BoxContaining(boxes, m.X);
      if (m.aoi.empty()) m.aoi = "outside";
      continue;
    }
    m.aoi = labels ? "unknown" : "surface";
    if (!labels) continue;
    std::vector<const SourceHit*> by_depth;
    for (const SourceHit& s : m.sources) by_depth.push_back(&s);
    std::stable_sort(by_depth.begin(), by_depth.end(),
                     [](const SourceHit* a, const SourceHit* b) { return a->depth < b->depth; });
    for (const SourceHit* s : by_depth)
      if (const Image* l = cache.Labels(s->view)) {
        m.aoi = CamVidClassName(static_cast<int>(
            l->at(static_cast<int>(std::floor(s->u)), static_cast<int>(std::floor(s->v)))));
        break;
      }
  }
  return !boxes.empty() ? "boxes " + o.aoi_boxes : labels ? "labels" : "none";
}

void WriteTables(const fs::path& out, const std::vector<Mapped>& mapped,
                 const std::vector<SourceView>& views, const std::vector<DwellRow>& aoi) {
  WriteTextAtomic(out / "sources.tsv", [&](std::ostream& s) {
    s << "fixation\timage\tu\tv\tdepth\n";
    for (size_t i = 0; i < mapped.size(); ++i)
      for (const SourceHit& h : mapped[i].sources)
        s << i + 1 << '\t' << views[h.view].name << '\t' << Fmt("%.3f", h.u) << '\t'
          << Fmt("%.3f", h.v) << '\t' << Fmt("%.9g", h.depth) << '\n';
  });
  WriteTextAtomic(out / "aoi.tsv", [&](std::ostream& s) { s << FormatDwellTable(aoi); });
  WriteTextAtomic(out / "fixations.tsv", [&](std::ostream& s) {
    s << "fixation\tstart\tend\tduration\tx\ty\tframe\tX\tY\tZ\tdistance\taoi\tsources\n";
    for (size_t i = 0; i < mapped.size(); ++i) {
      const Mapped& m = mapped[i];
      s << i + 1 << '\t' << Fmt("%.6f", m.f.start) << '\t' << Fmt("%.6f", m.f.end) << '\t'
        << Fmt("%.6f", m.f.duration()) << '\t' << Fmt("%.3f", m.f.x) << '\t' << Fmt("%.3f", m.f.y)
        << '\t' << m.frame << '\t' << FormatDouble(m.X.x()) << '\t' << FormatDouble(m.X.y()) << '\t'
        << FormatDouble(m.X.z()) << '\t' << FormatDouble(m.distance) << '\t' << m.aoi << '\t'
        << m.sources.size() << '\n';
    }
  });
}

size_t WritePictures(const fs::path& out, const std::vector<Mapped>& mapped,
                     const std::vector<SourceView>& views, const Workspace& ws,
                     const Mesh& mesh_data, const MeshRaycaster& mesh, const Frames& frames,
                     const GazemapOptions& o) {
  std::map<size_t, std::vector<FixationMark>> marks;
  std::vector<HeatPoint> heat;
  for (size_t i = 0; i < mapped.size(); ++i) {
    for (const SourceHit& h : mapped[i].sources)
      marks[h.view].push_back({h.u, h.v, std::to_string(i + 1)});
    if (mapped[i].hit) heat.push_back({mapped[i].X, mapped[i].f.duration()});
  }
  size_t written = 0;
  for (const auto& [view, list] : marks) {
    Image img = ReadImage(ws.SourceImagePath(views[view].name).string());
    DrawFixations(img, list);
    fs::path name(views[view].name);
    name.replace_extension(".png");
    WriteImage((out / "fixations" / name).string(), img);
    ++written;
  }
  std::vector<Eigen::Vector3d> path;
  std::vector<Rigid3d> w2c;
  for (const Rigid3d& p : frames.w2c) path.push_back(p.Centre());
  for (const SourceView& v : views) w2c.push_back(v.w2c);
  const Image map = RenderHeatmap(mesh_data, mesh, RecordedUp(w2c), path, heat,
                                  {o.heatmap_size, o.heatmap_sigma});
  WriteImage((out / "heatmap.png").string(), map);
  return written + 1;
}

void WriteGazeProvenance(const Workspace& ws, const GazemapOptions& o,
                         const std::vector<fs::path>& inputs) {
  const nlohmann::json opts = {{"frames", o.frames},
                               {"gaze", o.gaze},
                               {"out", o.out},
                               {"frame_rate", o.frame_rate},
                               {"screen", o.screen},
                               {"screen_mm", o.screen_mm},
                               {"distance", o.distance},
                               {"px_per_degree", o.px_per_degree},
                               {"max_gap", o.max_gap},
                               {"noise_median", o.noise_median},
                               {"velocity_window", o.velocity_window},
                               {"threshold", o.threshold},
                               {"merge_time", o.merge_time},
                               {"merge_angle", o.merge_angle},
                               {"min_duration", o.min_duration},
                               {"visibility", o.visibility},
                               {"depth_tolerance", o.depth_tolerance},
                               {"aoi_boxes", o.aoi_boxes},
                               {"heatmap_size", o.heatmap_size},
                               {"heatmap_sigma", o.heatmap_sigma},
                               {"no_pictures", o.no_pictures}};
  ws.WriteProvenance("gazemap", opts, inputs);
}

IvtOptions ToIvt(const GazemapOptions& o) {
  IvtOptions v;
  v.max_gap = o.max_gap / 1000;
  v.median_window = o.noise_median;
  v.velocity_window = o.velocity_window / 1000;
  v.threshold = o.threshold;
  v.merge_time = o.merge_time / 1000;
  v.merge_angle = o.merge_angle;
  v.min_duration = o.min_duration / 1000;
  return v;
}

}  // namespace

std::string FormatDwellTable(const std::vector<DwellRow>& rows) {
  std::string s = "aoi\tfixations\tdwell\tshare\n";
  for (const DwellRow& r : rows)
    s += r.aoi + '\t' + std::to_string(r.fixations) + '\t' + Fmt("%.3f", r.dwell) + '\t' +
         Fmt("%.3f", r.share) + '\n';
  return s;
}

void GazemapOptions::Check() const {
  if (out.empty()) throw UsageError("OUT is required");
  if (frame_rate != 0) CheckRange(frame_rate, 0, 10000, true, "--frame-rate (Hz)");
  if (!screen.empty()) ParseWH(screen, "--screen");
  const bool physical = !screen_mm.empty() || distance != 0;
  if (physical && px_per_degree != 0)
    throw UsageError("give --screen-mm and --distance, or --px-per-degree, not both");
  if (physical) {
    if (screen_mm.empty() || distance == 0)
      throw UsageError("--screen-mm and --distance go together");
    ParseWH(screen_mm, "--screen-mm");
    CheckRange(distance, 0, 1e5, true, "--distance (mm)");
  } else if (px_per_degree == 0) {
    throw UsageError(
        "the eye-to-screen geometry is needed for angles: give --screen-mm WxH and --distance "
        "MM, or --px-per-degree P");
  } else {
    CheckRange(px_per_degree, 0, 1e5, true, "--px-per-degree");
  }
  CheckRange(max_gap, 0, 1000, false, "--max-gap (ms)");
  if (noise_median != 0 && (noise_median < 3 || noise_median > 99 || noise_median % 2 == 0))
    throw UsageError("--noise-median: must be 0 (off) or odd in [3, 99]");
  CheckRange(velocity_window, 0, 1000, true, "--velocity-window (ms)");
  CheckRange(threshold, 0, 10000, true, "--threshold (deg/s)");
  CheckRange(merge_time, 0, 1000, false, "--merge-time (ms)");
  CheckRange(merge_angle, 0, 180, false, "--merge-angle (deg)");
  CheckRange(min_duration, 0, 10000, false, "--min-duration (ms)");
  CheckChoice(visibility, kGazeVisibility, "--visibility");
  CheckRange(depth_tolerance, 0, 1, false, "--depth-tolerance");
  CheckRange(heatmap_size, 16, 16384, false, "--heatmap-size (px)");
  CheckRange(heatmap_sigma, 0, 1e12, false, "--heatmap-sigma");
}

GazemapReport RunGazemap(const GazemapOptions& o) {
  o.Check();
  GazemapReport rep;
  const GazeTrace gaze = ReadGazeTsv(o.gaze);  // a bad trace fails first, fast
  rep.ignored_columns = gaze.ignored;
  rep.samples = gaze.samples.size();
  rep.invalid_flagged = gaze.invalid_flagged;
  rep.invalid_nonfinite = gaze.invalid_nonfinite;
  const std::vector<AoiBox> boxes =
      o.aoi_boxes.empty() ? std::vector<AoiBox>{} : ReadAoiBoxes(o.aoi_boxes);
  const Workspace ws(o.workspace);
  ws.Require("gazemap", {WsItem::kSparse, WsItem::kMesh});
  std::vector<fs::path> inputs = ws.SparseModelFiles();
  for (const std::string& p : {ws.MeshPath().string(), o.frames, o.gaze, o.aoi_boxes})
    if (!p.empty()) inputs.emplace_back(p);
  // Baked depth and labels decide sources and AOIs; their folders change with every atomic
  // rename of a file in them (a rerun of bakedepth or segtrack).
  inputs.push_back(ws.DepthDir());
  inputs.push_back(ws.LabelsDir());
  const fs::path out(o.out);
  if (!o.force && IsUpToDate(out / "fixations.tsv", inputs)) {
    rep.up_to_date = true;
    return rep;
  }
  const Frames frames = LoadFrames(o);
  CheckGazeTimes(gaze, *frames.clock, o);
  const Reconstruction rec = ReadColmapModel(ws.SparseDir().string());
  if (rec.cameras.empty()) throw Error(ws.SparseDir().string(), 0, "the model has no cameras");
  const Camera render = rec.cameras.begin()->second;
  render.RequireUndistorted();
  const ScreenGeometry screen = MakeScreen(o, render);
  const IvtResult ivt = RunIvt(gaze.samples, screen, ToIvt(o));
  rep.gaps_filled = ivt.gaps_filled;
  rep.samples_filled = ivt.samples_filled;
  rep.merged = ivt.merged;
  rep.discarded = ivt.discarded;
  rep.fixations = ivt.fixations.size();
  const Mesh mesh_data = ReadMesh(ws.MeshPath().string());
  const MeshRaycaster mesh(mesh_data);
  const std::vector<SourceView> views = LoadViews(rec);
  MapCache cache(ws, views);
  std::vector<Mapped> mapped = MapFixations(ivt, frames, render, screen, mesh, views, cache, o);
  rep.aoi_from = AssignAois(mapped, boxes, cache, ws, o);
  std::vector<std::string> names;
  std::vector<double> durations;
  for (const Mapped& m : mapped) {
    rep.on_mesh += m.hit;
    rep.with_source += !m.sources.empty();
    rep.source_rows += m.sources.size();
    names.push_back(m.aoi);
    durations.push_back(m.f.duration());
  }
  rep.aoi = DwellTable(names, durations);
  CreateFolder(out);
  if (!o.no_pictures)
    rep.pictures = WritePictures(out, mapped, views, ws, mesh_data, mesh, frames, o);
  WriteTables(out, mapped, views, rep.aoi);  // fixations.tsv last: it marks the run complete
  WriteGazeProvenance(ws, o, inputs);
  return rep;
}

}  // namespace mvtm
