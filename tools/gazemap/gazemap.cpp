#include "gazemap.h"

#include <cmath>
#include <cstdio>
#include <fstream>
#include <iostream>
#include <map>
#include <memory>
#include <set>

#include "base/atomic_file.h"
#include "base/error.h"
#include "base/text.h"
#include "cli/work.h"
#include "drive/ground.h"
#include "gaze/fixation_map.h"
#include "gaze/gaze_tsv.h"
#include "gaze/ivt.h"
#include "gaze/mapping.h"
#include "gaze/pictures.h"
#include "io/colmap_model.h"
#include "io/mesh_io.h"
#include "io/trajectory.h"
#include "run/ledger.h"
#include "workspace/assets.h"
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

// Depth maps and label images read on first use, at their camera's size (workspace/assets.h:
// depth baked at any --scale reads as ptmrender reads it).
class MapCache {
 public:
  MapCache(const Workspace& ws, const std::vector<SourceView>& views) : ws_(ws), views_(views) {}
  const Image* Depth(size_t i) { return Get(depth_, i, ReadDepthAtCamera); }
  const Image* Labels(size_t i) { return Get(labels_, i, ReadLabelsAtCamera); }

 private:
  using Reader = Image (*)(const Workspace&, const std::string&, const Camera&);
  const Image* Get(std::map<size_t, std::unique_ptr<Image>>& m, size_t i, Reader read) {
    auto it = m.find(i);
    if (it != m.end()) return it->second.get();
    Image img = read(ws_, views_[i].name, views_[i].camera);
    std::unique_ptr<Image> p = img.empty() ? nullptr : std::make_unique<Image>(std::move(img));
    return m.emplace(i, std::move(p)).first->second.get();
  }
  const Workspace& ws_;
  const std::vector<SourceView>& views_;
  std::map<size_t, std::unique_ptr<Image>> depth_, labels_;
};

// Each output this run may write → whether it must be (re)made: the ledger is asked once per
// output, so its reasons are counted once.
struct OutputPlan {
  Ledger& ledger;
  bool force = false;
  std::map<fs::path, bool> stale;
  std::set<std::string> pictured;  // the photos the last sources.tsv names (its pictures)

  bool Need(const fs::path& p, const std::vector<fs::path>& item_inputs = {}) {
    auto it = stale.find(p);
    if (it == stale.end())
      it = stale.emplace(p, !ledger.Stale(p, item_inputs, force).empty()).first;
    return it->second;
  }
};

fs::path PicturePath(const fs::path& out, const std::string& image) {
  fs::path name(image);
  name.replace_extension(".png");
  return out / "fixations" / name;
}

// The photos a sources.tsv names (its image column): the run that wrote it drew on those.
std::set<std::string> PicturedImages(const fs::path& sources) {
  std::set<std::string> names;
  std::ifstream in(sources);
  std::string line;
  std::getline(in, line);  // the header
  while (std::getline(in, line)) {
    const auto f = SplitChar(line, '\t');
    if (f.size() >= 2) names.insert(std::string(f[1]));
  }
  return names;
}

// Asks about every output known before the fixations are mapped: the tables, the heat map and,
// when sources.tsv is up to date (so made from these inputs), the pictures of the photos it
// names. True when any must be made.
bool PlanOutputs(const GazemapOptions& o, const Workspace& ws, OutputPlan& plan) {
  const fs::path out(o.out);
  bool any = false;
  for (const char* table : {"sources.tsv", "aoi.tsv", "fixations.tsv"})
    any = plan.Need(out / table) || any;
  if (o.no_pictures) return any;
  any = plan.Need(out / "heatmap.png") || any;
  plan.pictured = PicturedImages(out / "sources.tsv");
  if (plan.Need(out / "sources.tsv")) return true;
  for (const std::string& image : plan.pictured)
    any = plan.Need(PicturePath(out, image), {ws.SourceImagePath(image)}) || any;
  return any;
}

// Writes `path` atomically when the plan says it must be made, and records it.
void WriteTable(OutputPlan& plan, const fs::path& path,
                const std::function<void(std::ostream&)>& write) {
  if (!plan.Need(path)) return;
  WriteTextAtomic(path, write);
  plan.ledger.Done(path);
}

void WriteTables(const fs::path& out, const std::vector<MappedFixation>& mapped,
                 const std::vector<SourceView>& views, const std::vector<DwellRow>& aoi,
                 OutputPlan& plan) {
  WriteTable(plan, out / "sources.tsv", [&](std::ostream& s) {
    s << "fixation\timage\tu\tv\tdepth\n";
    for (size_t i = 0; i < mapped.size(); ++i)
      for (const SourceHit& h : mapped[i].sources)
        s << i + 1 << '\t' << views[h.view].name << '\t' << Fmt("%.3f", h.u) << '\t'
          << Fmt("%.3f", h.v) << '\t' << Fmt("%.9g", h.depth) << '\n';
  });
  WriteTable(plan, out / "aoi.tsv", [&](std::ostream& s) { s << FormatDwellTable(aoi); });
  WriteTable(plan, out / "fixations.tsv", [&](std::ostream& s) {
    s << "fixation\tstart\tend\tduration\tx\ty\tframe\tX\tY\tZ\tdistance\taoi\tsources\n";
    for (size_t i = 0; i < mapped.size(); ++i) {
      const MappedFixation& m = mapped[i];
      const Fixation& f = m.fixation;
      s << i + 1 << '\t' << Fmt("%.6f", f.start) << '\t' << Fmt("%.6f", f.end) << '\t'
        << Fmt("%.6f", f.duration()) << '\t' << Fmt("%.3f", f.x) << '\t' << Fmt("%.3f", f.y) << '\t'
        << m.frame << '\t' << FormatDouble(m.X.x()) << '\t' << FormatDouble(m.X.y()) << '\t'
        << FormatDouble(m.X.z()) << '\t' << FormatDouble(m.distance) << '\t' << m.aoi << '\t'
        << m.sources.size() << '\n';
    }
  });
}

// What the fixations were mapped with, for the pictures.
struct MappedScene {
  const Workspace& ws;
  const std::vector<SourceView>& views;
  const Mesh& mesh_data;
  const MeshRaycaster& mesh;
  const Frames& frames;
};

size_t WritePictures(const fs::path& out, const std::vector<MappedFixation>& mapped,
                     const MappedScene& scene, const GazemapOptions& o, OutputPlan& plan) {
  std::map<size_t, std::vector<FixationMark>> marks;
  std::vector<HeatPoint> heat;
  for (size_t i = 0; i < mapped.size(); ++i) {
    for (const SourceHit& h : mapped[i].sources)
      marks[h.view].push_back({h.u, h.v, std::to_string(i + 1)});
    if (mapped[i].hit) heat.push_back({mapped[i].X, mapped[i].fixation.duration()});
  }
  size_t written = 0;
  std::set<std::string> drawn;
  for (const auto& [view, list] : marks) {
    const fs::path photo = scene.ws.SourceImagePath(scene.views[view].name);
    const fs::path picture = PicturePath(out, scene.views[view].name);
    drawn.insert(scene.views[view].name);
    if (!plan.Need(picture, {photo})) continue;
    Image img = ReadImage(photo.string());
    DrawFixations(img, list);
    WriteImage(picture.string(), img);
    plan.ledger.Done(picture, {photo});
    ++written;
  }
  // The last run's pictures of photos this run draws on no more go: OUT/fixations is this run's.
  std::error_code ec;
  for (const std::string& image : plan.pictured)
    if (!drawn.count(image)) fs::remove(PicturePath(out, image), ec);
  const fs::path heatmap = out / "heatmap.png";
  if (!plan.Need(heatmap)) return written;
  std::vector<Eigen::Vector3d> path;
  std::vector<Rigid3d> w2c;
  for (const Rigid3d& p : scene.frames.w2c) path.push_back(p.Centre());
  for (const SourceView& v : scene.views) w2c.push_back(v.w2c);
  const Image map = RenderHeatmap(scene.mesh_data, scene.mesh, RecordedUp(w2c), path, heat,
                                  {o.heatmap_size, o.heatmap_sigma});
  WriteImage(heatmap.string(), map);
  plan.ledger.Done(heatmap);
  return written + 1;
}

// Where gazemap's record goes: the workspace when OUT is inside it, else OUT.
fs::path RecordRoot(const GazemapOptions& o, const Workspace& ws) {
  const fs::path rel =
      fs::weakly_canonical(o.out).lexically_relative(fs::weakly_canonical(ws.root()));
  const bool inside = !rel.empty() && rel.begin()->string() != "..";
  return inside ? ws.root() : fs::path(o.out);
}

// Every file all outputs depend on: the sparse model, the mesh, FRAMES, GAZE, the boxes, the
// depth maps (--visibility depth) and the label images (without boxes) of the model's images.
std::vector<fs::path> GazeInputs(const GazemapOptions& o, const Workspace& ws,
                                 const Reconstruction& rec) {
  std::vector<fs::path> inputs = ws.SparseModelFiles();
  for (const std::string& p : {ws.MeshPath().string(), o.frames, o.gaze, o.aoi_boxes})
    if (!p.empty()) inputs.emplace_back(p);
  for (const ImageRecord* im : rec.ImagesByName()) {
    if (o.visibility == GazeVisibility::kDepth) inputs.push_back(ws.DepthPath(im->name));
    if (o.aoi_boxes.empty()) inputs.push_back(ws.LabelPath(im->name));
  }
  return inputs;
}

// The I-VT filter's options (Tobii's defaults).
void DeclareIvtOptions(OptionTable& t, GazemapOptions& o) {
  t.Real("--max-gap", &o.max_gap, "I-VT gap fill-in: fill gaps up to this, ms (0: off)")
      .Range(0, 1000);
  t.Integer("--noise-median", &o.noise_median,
            "I-VT noise reduction: moving-median window in samples, odd (0: off)")
      .Range(0, 99)
      .Alternative("3")
      .Check([&o] {
        if (o.noise_median != 0 && (o.noise_median < 3 || o.noise_median % 2 == 0))
          throw UsageError("--noise-median: must be 0 (off) or odd in [3, 99]");
      });
  t.Real("--velocity-window", &o.velocity_window, "I-VT velocity window, ms (at least 3 samples)")
      .Range(0, 1000, true);
  t.Real("--threshold", &o.threshold, "I-VT velocity threshold, degrees per second")
      .Range(0, 10000, true);
  t.Real("--merge-time", &o.merge_time,
         "Merge adjacent fixations less than this apart, ms (0: off)")
      .Range(0, 1000);
  t.Real("--merge-angle", &o.merge_angle, "... and less than this apart in visual angle, degrees")
      .Range(0, 180);
  t.Real("--min-duration", &o.min_duration, "Discard fixations shorter than this, ms (0: keep all)")
      .Range(0, 10000);
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

// The fixations mapped onto the mesh and the photos, with their AOIs; the counts into `rep`.
std::vector<MappedFixation> MapAndAssign(const IvtResult& ivt, const ShownFrames& shown,
                                         const MeshRaycaster& mesh,
                                         const std::vector<SourceView>& views,
                                         const std::vector<AoiBox>& boxes, const Workspace& ws,
                                         const GazemapOptions& o, GazemapReport& rep) {
  MapCache cache(ws, views);
  const DepthLookup depth = [&](size_t i) {
    return o.visibility == GazeVisibility::kDepth ? cache.Depth(i) : nullptr;
  };
  std::vector<MappedFixation> mapped =
      MapFixations(ivt.fixations, shown, mesh, views, depth, {o.depth_tolerance, 1e-3});
  const bool labels = boxes.empty() && fs::is_directory(ws.LabelsDir());
  LabelLookup label_lookup;
  if (labels) label_lookup = [&](size_t i) { return cache.Labels(i); };
  AssignAois(mapped, boxes, label_lookup);
  rep.aoi_from = !boxes.empty() ? "boxes " + o.aoi_boxes : labels ? "labels" : "none";
  std::vector<std::string> names;
  std::vector<double> durations;
  for (const MappedFixation& m : mapped) {
    rep.on_mesh += m.hit;
    rep.with_source += !m.sources.empty();
    rep.source_rows += m.sources.size();
    names.push_back(m.aoi);
    durations.push_back(m.fixation.duration());
  }
  rep.aoi = DwellTable(names, durations);
  return mapped;
}

// Maps the gaze and writes the outputs the plan says must be made.
void MakeOutputs(const GazeTrace& gaze, const Reconstruction& rec, const std::vector<AoiBox>& boxes,
                 const Workspace& ws, const GazemapOptions& o, OutputPlan& plan,
                 GazemapReport& rep) {
  const Frames frames = LoadFrames(o);
  CheckGazeTimes(gaze, *frames.clock, o);
  if (rec.cameras.empty()) throw Error(ws.SparseDir().string(), 0, "the model has no cameras");
  const Camera render = rec.RenderCamera();
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
  const std::vector<MappedFixation> mapped = MapAndAssign(
      ivt, ShownFrames{*frames.clock, frames.w2c, render, screen}, mesh, views, boxes, ws, o, rep);
  const fs::path out(o.out);
  CreateFolder(out);
  if (!o.no_pictures)
    rep.pictures =
        WritePictures(out, mapped, MappedScene{ws, views, mesh_data, mesh, frames}, o, plan);
  WriteTables(out, mapped, views, rep.aoi, plan);
}

}  // namespace

std::string FormatDwellTable(const std::vector<DwellRow>& rows) {
  std::string s = "aoi\tfixations\tdwell\tshare\n";
  for (const DwellRow& r : rows)
    s += r.aoi + '\t' + std::to_string(r.fixations) + '\t' + Fmt("%.3f", r.dwell) + '\t' +
         Fmt("%.3f", r.share) + '\n';
  return s;
}

OptionTable DeclareOptions(GazemapOptions& o) {
  OptionTable t("gazemap");
  t.Positional("WS", &o.workspace, "Workspace folder (sparse/, mesh.ply; depth/, labels/ used)")
      .Dir();
  t.Positional("FRAMES", &o.frames,
               "The poses the frames were rendered at (ptmrender --poses: TUM, whose timestamps "
               "are the display times, KITTI or COLMAP images.txt with --frame-rate)")
      .File();
  t.Positional("GAZE", &o.gaze,
               "Gaze trace: a header naming 'time x y [valid]' (seconds, screen pixels, 0/1), "
               "then one row per sample")
      .File();
  t.Positional("OUT", &o.out, "Output folder (fixations.tsv, sources.tsv, aoi.tsv, pictures)")
      .Dir();
  t.Real("--frame-rate", &o.frame_rate,
         "Frames per second: frame i is shown at i/HZ seconds (instead of FRAMES' times)")
      .Range(0, 10000);  // 0: FRAMES' times
  t.Text("--screen", &o.screen,
         "WxH: the screen in pixels, the render shown full screen (default: the render camera's "
         "size)")
      .Alternative("1920x1080")
      .Check([&o] {
        if (!o.screen.empty()) ParseWH(o.screen, "--screen");
      });
  t.Text("--screen-mm", &o.screen_mm, "WxH: the screen's physical size in millimetres")
      .Alternative("531x299")
      .Check([&o] {
        if (!o.screen_mm.empty()) ParseWH(o.screen_mm, "--screen-mm");
      });
  t.Real("--distance", &o.distance, "Eye to screen centre, millimetres (with --screen-mm)")
      .Range(0, 1e5);  // 0: not given
  t.Real("--px-per-degree", &o.px_per_degree,
         "Screen pixels per degree of visual angle (instead of --screen-mm, --distance)")
      .Range(0, 1e5);  // 0: not given
  DeclareIvtOptions(t, o);
  t.Choice("--visibility", &o.visibility, kGazeVisibility,
           "depth: a photo's baked depth map (WS/depth) decides if it sees the point, a ray where "
           "it has none; ray: always a ray against the mesh");
  t.Real("--depth-tolerance", &o.depth_tolerance, "Relative depth tolerance of the depth-map test")
      .Range(0, 1);
  t.Text("--aoi-boxes", &o.aoi_boxes,
         "Areas of interest from 3-D boxes: lines 'name xmin ymin zmin xmax ymax zmax' (default: "
         "classes of the label images WS/labels)")
      .File();
  t.Integer("--heatmap-size", &o.heatmap_size, "Heat map's larger side, pixels").Range(16, 16384);
  t.Real("--heatmap-sigma", &o.heatmap_sigma, "Heat map Gaussian, model units (0: 1% of the map)")
      .Range(0, 1e12);
  // Which outputs are written, not what any of them holds.
  t.Flag("--no-pictures", &o.no_pictures, "Write the tables only (no PNGs)").Cosmetic();
  t.Flag("--force", &o.force, "Rewrite OUT's files even when they are up to date").Cosmetic();
  DeclareQuietOption(t, o.quiet);
  return t;
}

void GazemapOptions::Check() const {
  CheckDeclared(*this);
  const bool physical = !screen_mm.empty() || distance != 0;
  if (physical && px_per_degree != 0)
    throw UsageError("give --screen-mm and --distance, or --px-per-degree, not both");
  if (physical && (screen_mm.empty() || distance == 0))
    throw UsageError("--screen-mm and --distance go together");
  if (!physical && px_per_degree == 0)
    throw UsageError(
        "the eye-to-screen geometry is needed for angles: give --screen-mm WxH and --distance "
        "MM, or --px-per-degree P");
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
  const Reconstruction rec = ReadColmapModel(ws.SparseDir().string());
  GazemapOptions resolved = o;
  const OptionTable table = DeclareOptions(resolved);
  Ledger ledger(RecordRoot(o, ws), "gazemap", table, GazeInputs(o, ws, rec), ws.root());
  OutputPlan plan{ledger, o.force, {}, {}};
  if (!PlanOutputs(o, ws, plan)) {
    rep.up_to_date = true;
    return rep;
  }
  MakeOutputs(gaze, rec, boxes, ws, o, plan, rep);
  ledger.Write();
  rep.why = ledger.Summary();
  return rep;
}

void PrintGazemapReport(const GazemapOptions& o, const GazemapReport& r) {
  if (!o.quiet && !r.ignored_columns.empty()) {
    std::string cols;
    for (const auto& c : r.ignored_columns) cols += (cols.empty() ? "" : " ") + c;
    std::fprintf(stderr, "gazemap: note: %s: columns not used: %s\n", o.gaze.c_str(), cols.c_str());
  }
  if (r.up_to_date) {
    // The table of the run that wrote OUT, as a fresh run prints it.
    std::ifstream table(fs::path(o.out) / "aoi.tsv");
    std::cout << table.rdbuf() << std::flush;
    if (!o.quiet)
      std::fprintf(stderr, "gazemap: %s is up to date (--force rewrites)\n", o.out.c_str());
    return;
  }
  std::fputs(FormatDwellTable(r.aoi).c_str(), stdout);
  if (o.quiet) return;
  std::fprintf(stderr,
               "gazemap: %zu samples (%zu invalid: %zu flagged, %zu not finite; %zu filled in "
               "%zu gaps); %zu fixations (%zu merges, %zu discarded as short); %zu on the "
               "mesh, %zu seen by a photo (%zu sources); AOIs: %s; %zu pictures",
               r.samples, r.invalid_flagged + r.invalid_nonfinite, r.invalid_flagged,
               r.invalid_nonfinite, r.samples_filled, r.gaps_filled, r.fixations, r.merged,
               r.discarded, r.on_mesh, r.with_source, r.source_rows, r.aoi_from.c_str(),
               r.pictures);
  if (!r.why.empty()) std::fprintf(stderr, " [%s]", r.why.c_str());
  std::fprintf(stderr, "\n");
}

}  // namespace mvtm
