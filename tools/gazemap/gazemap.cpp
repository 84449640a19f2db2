#include "gazemap.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <functional>
#include <iostream>
#include <map>
#include <memory>
#include <optional>
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
#include "workspace/road.h"
#include "workspace/road_locator.h"
#include "workspace/road_meshes.h"
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

// The workspace holding view i's files (the workspace, or on a road the fragment owning it).
using WorkspaceOf = std::function<const Workspace&(size_t view)>;
// Where the photo of an image is on disk.
using PhotoOf = std::function<fs::path(const std::string& image)>;

// Depth maps and label images read on first use, at their camera's size (workspace/assets.h:
// depth baked at any --scale reads as ptmrender reads it).
class MapCache {
 public:
  MapCache(const std::vector<SourceView>& views, WorkspaceOf ws_of)
      : views_(views), ws_of_(std::move(ws_of)) {}
  const Image* Depth(size_t i) { return Get(depth_, i, ReadDepthAtCamera); }
  const Image* Labels(size_t i) { return Get(labels_, i, ReadLabelsAtCamera); }

 private:
  using Reader = Image (*)(const Workspace&, const std::string&, const Camera&);
  const Image* Get(std::map<size_t, std::unique_ptr<Image>>& m, size_t i, Reader read) {
    auto it = m.find(i);
    if (it != m.end()) return it->second.get();
    Image img = read(ws_of_(i), views_[i].name, views_[i].camera);
    std::unique_ptr<Image> p = img.empty() ? nullptr : std::make_unique<Image>(std::move(img));
    return m.emplace(i, std::move(p)).first->second.get();
  }
  const std::vector<SourceView>& views_;
  WorkspaceOf ws_of_;
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
bool PlanOutputs(const GazemapOptions& o, const PhotoOf& photo, OutputPlan& plan) {
  const fs::path out(o.out);
  bool any = false;
  for (const char* table : {"sources.tsv", "aoi.tsv", "fixations.tsv"})
    any = plan.Need(out / table) || any;
  if (o.no_pictures) return any;
  any = plan.Need(out / "heatmap.png") || any;
  plan.pictured = PicturedImages(out / "sources.tsv");
  if (plan.Need(out / "sources.tsv")) return true;
  for (const std::string& image : plan.pictured)
    any = plan.Need(PicturePath(out, image), {photo(image)}) || any;
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

// What the fixations were mapped with, for the pictures: the photos, and the surfaces of the
// heat map (the mesh, or a road's fragments one by one).
struct MappedScene {
  const std::vector<SourceView>& views;
  PhotoOf photo;
  std::function<void(HeatmapPainter&)> surfaces;
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
    const fs::path photo = scene.photo(scene.views[view].name);
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
  HeatmapPainter painter(RecordedUp(w2c), std::move(path), std::move(heat),
                         {o.heatmap_size, o.heatmap_sigma});
  scene.surfaces(painter);
  WriteImage(heatmap.string(), painter.Finish());
  plan.ledger.Done(heatmap);
  return written + 1;
}

// Where gazemap's record goes: the workspace (or road) when OUT is inside it, else OUT.
fs::path RecordRoot(const GazemapOptions& o, const fs::path& root) {
  const fs::path rel = fs::weakly_canonical(o.out).lexically_relative(fs::weakly_canonical(root));
  const bool inside = !rel.empty() && rel.begin()->string() != "..";
  return inside ? root : fs::path(o.out);
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

// The fixations' counts and the dwell table into `rep`.
void Tally(const std::vector<MappedFixation>& mapped, GazemapReport& rep) {
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
}

// The fixations mapped onto `mesh` and the photos `views` (files in ws_of(view)), with their AOIs.
std::vector<MappedFixation> MapAndAssign(const std::vector<Fixation>& fixations,
                                         const ShownFrames& shown, const MeshRaycaster& mesh,
                                         const std::vector<SourceView>& views,
                                         const std::vector<AoiBox>& boxes, bool labels,
                                         const WorkspaceOf& ws_of, const GazemapOptions& o) {
  MapCache cache(views, ws_of);
  const DepthLookup depth = [&](size_t i) {
    return o.visibility == GazeVisibility::kDepth ? cache.Depth(i) : nullptr;
  };
  std::vector<MappedFixation> mapped =
      MapFixations(fixations, shown, mesh, views, depth, {o.depth_tolerance, 1e-3});
  LabelLookup label_lookup;
  if (labels) label_lookup = [&](size_t i) { return cache.Labels(i); };
  AssignAois(mapped, boxes, label_lookup);
  return mapped;
}

std::string AoiFrom(const std::vector<AoiBox>& boxes, bool labels, const GazemapOptions& o) {
  return !boxes.empty() ? "boxes " + o.aoi_boxes : labels ? "labels" : "none";
}

// The I-VT fixations of the gaze on `screen`; the filter's counts into `rep`.
IvtResult Fixate(const GazeTrace& gaze, const ScreenGeometry& screen, const GazemapOptions& o,
                 GazemapReport& rep) {
  IvtResult ivt = RunIvt(gaze.samples, screen, ToIvt(o));
  rep.gaps_filled = ivt.gaps_filled;
  rep.samples_filled = ivt.samples_filled;
  rep.merged = ivt.merged;
  rep.discarded = ivt.discarded;
  rep.fixations = ivt.fixations.size();
  return ivt;
}

// Writes the pictures and the tables the plan says must be made.
void WriteOutputs(const std::vector<MappedFixation>& mapped, const MappedScene& scene,
                  const GazemapOptions& o, OutputPlan& plan, GazemapReport& rep) {
  const fs::path out(o.out);
  CreateFolder(out);
  if (!o.no_pictures) rep.pictures = WritePictures(out, mapped, scene, o, plan);
  WriteTables(out, mapped, scene.views, rep.aoi, plan);
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
  const IvtResult ivt = Fixate(gaze, screen, o, rep);
  const Mesh mesh_data = ReadMesh(ws.MeshPath().string());
  const MeshRaycaster mesh(mesh_data);
  const std::vector<SourceView> views = LoadViews(rec);
  const bool labels = boxes.empty() && fs::is_directory(ws.LabelsDir());
  const std::vector<MappedFixation> mapped = MapAndAssign(
      ivt.fixations, ShownFrames{*frames.clock, frames.w2c, render, screen}, mesh, views, boxes,
      labels, [&](size_t) -> const Workspace& { return ws; }, o);
  rep.aoi_from = AoiFrom(boxes, labels, o);
  Tally(mapped, rep);
  const MappedScene scene{
      views, [&](const std::string& image) { return ws.SourceImagePath(image); },
      [&](HeatmapPainter& painter) { painter.AddSurface(mesh_data, mesh); }, frames};
  WriteOutputs(mapped, scene, o, plan, rep);
}

// ---- a road (ROAD/Graph.txt): fragments streamed by the graph --------------------------------

// The road's photos: every fragment's own images, each once, with the fragment holding its files.
struct RoadPhotos {
  std::vector<Workspace> fragments;        // one per fragment of the road
  std::vector<SourceView> views;           // name order, as a workspace's (LoadViews)
  std::vector<size_t> owner;               // the fragment of each view
  std::vector<std::vector<size_t>> owned;  // each fragment's views

  explicit RoadPhotos(const RoadLocator& where) : owned(where.road().fragments().size()) {
    for (const RoadFragment& f : where.road().fragments()) fragments.emplace_back(f.dir);
    std::vector<const RoadRecordedFrame*> frames;
    for (const RoadRecordedFrame& f : where.frames()) frames.push_back(&f);
    std::sort(frames.begin(), frames.end(),
              [](auto* a, auto* b) { return a->image->name < b->image->name; });
    for (const RoadRecordedFrame* fp : frames) {
      const RoadRecordedFrame& f = *fp;
      const ImageRecord& im = *f.image;
      const Camera& cam = where.model(f.home).cameras.at(im.camera_id);
      cam.RequireUndistorted();
      owned[f.home].push_back(views.size());
      owner.push_back(f.home);
      views.push_back({im.name, cam,
                       Rigid3d(NormalizedQuaternion(im.world_to_camera.q), im.world_to_camera.t)});
    }
  }
  bool HasLabels() const {
    return std::any_of(fragments.begin(), fragments.end(),
                       [](const Workspace& w) { return fs::is_directory(w.LabelsDir()); });
  }
};

// Where each of the road's photos is: in the fragment that owns it (an image the road does not
// hold: a path that does not exist).
PhotoOf RoadPhotoOf(const Road& road) {
  auto where = std::make_shared<std::map<std::string, fs::path>>();
  for (const RoadFragment& f : road.fragments()) {
    const Workspace ws(f.dir);
    for (const std::string& name : f.owned_images) (*where)[name] = ws.SourceImagePath(name);
  }
  return [where, root = road.root()](const std::string& image) {
    const auto it = where->find(image);
    return it == where->end() ? root / image : it->second;
  };
}

// The fragment each frame's camera is in, walking the graph in the frames' order.
std::vector<size_t> FrameHomes(const Frames& frames, const RoadLocator& where,
                               const GazemapOptions& o) {
  std::vector<size_t> homes;
  std::optional<size_t> home;
  for (size_t i = 0; i < frames.w2c.size(); ++i) {
    home = where.Locate(frames.w2c[i].Centre(), home, o.frames + ": pose " + std::to_string(i + 1));
    homes.push_back(*home);
  }
  return homes;
}

// Runs of consecutive fixations whose frame's camera is in the same fragment.
struct FixationGroup {
  size_t home = 0, begin = 0, end = 0;
};

std::vector<FixationGroup> GroupByHome(const std::vector<Fixation>& fixations,
                                       const FrameClock& clock, const std::vector<size_t>& homes) {
  std::vector<FixationGroup> groups;
  for (size_t i = 0; i < fixations.size(); ++i) {
    const auto frame = clock.FrameAt((fixations[i].start + fixations[i].end) / 2);
    // A middle outside the frames stays with its group: MapFixations reports it.
    const size_t home = frame ? homes[*frame] : groups.empty() ? homes.front() : groups.back().home;
    if (groups.empty() || groups.back().home != home) groups.push_back({home, i, i});
    groups.back().end = i + 1;
  }
  return groups;
}

struct RoadRun {
  const Road& road;
  const RoadLocator& where;
  const RoadPhotos& photos;
  RoadMeshes& meshes;
};

// Maps each group's fixations on the mesh and photos of its fragment and its neighbours; the
// mesh of the next group is read on a second thread meanwhile.
std::vector<MappedFixation> MapOnRoad(const IvtResult& ivt, const Frames& frames,
                                      const ScreenGeometry& screen,
                                      const std::vector<size_t>& homes,
                                      const std::vector<AoiBox>& boxes, bool labels, RoadRun& run,
                                      const GazemapOptions& o) {
  const std::vector<FixationGroup> groups = GroupByHome(ivt.fixations, *frames.clock, homes);
  std::vector<MappedFixation> mapped;
  for (size_t g = 0; g < groups.size(); ++g) {
    const std::vector<size_t> resident = run.road.Resident(groups[g].home);
    const Mesh mesh =
        run.meshes.Union(resident, g + 1 < groups.size() ? run.road.Resident(groups[g + 1].home)
                                                         : std::vector<size_t>{});
    const MeshRaycaster raycaster(mesh);
    std::vector<SourceView> views;
    std::vector<size_t> global;
    for (size_t k : resident)
      global.insert(global.end(), run.photos.owned[k].begin(), run.photos.owned[k].end());
    std::sort(global.begin(), global.end());  // name order, as on a workspace
    for (size_t v : global) views.push_back(run.photos.views[v]);
    const Camera render = run.where.model(groups[g].home).RenderCamera();
    const std::vector<Fixation> part(ivt.fixations.begin() + groups[g].begin,
                                     ivt.fixations.begin() + groups[g].end);
    std::vector<MappedFixation> m = MapAndAssign(
        part, ShownFrames{*frames.clock, frames.w2c, render, screen}, raycaster, views, boxes,
        labels,
        [&](size_t i) -> const Workspace& {
          return run.photos.fragments[run.photos.owner[global[i]]];
        },
        o);
    for (MappedFixation& f : m) {
      for (SourceHit& h : f.sources) h.view = global[h.view];  // (order kept: global ascends)
      mapped.push_back(std::move(f));
    }
  }
  return mapped;
}

// The heat map's surfaces on a road: every fragment whose own triangles lie under the map (by
// the bounds in its fragment.json; one without bounds, or whose mesh was made anew since, is read
// to find out), read one at a time, the next on a second thread.
void PaintRoad(HeatmapPainter& painter, RoadRun& run) {
  std::vector<size_t> under;
  for (size_t k = 0; k < run.road.fragments().size(); ++k) {
    const RoadFragment& f = run.road.fragments()[k];
    const bool as_split = run.meshes.AsSplit(k);  // (a mesh made anew has other bounds)
    if (as_split && f.owned_faces == 0) continue;
    if (!as_split || !f.bounds || painter.CoversBox((*f.bounds)[0], (*f.bounds)[1]))
      under.push_back(k);
  }
  for (size_t i = 0; i < under.size(); ++i) {
    const Mesh mesh =
        run.meshes.Union({under[i]}, i + 1 < under.size() ? std::vector<size_t>{under[i + 1]}
                                                          : std::vector<size_t>{});
    if (!mesh.faces.empty()) painter.AddSurface(mesh, MeshRaycaster(mesh));
  }
}

void MakeRoadOutputs(const GazeTrace& gaze, const Road& road, const std::vector<AoiBox>& boxes,
                     const PhotoOf& photo, const GazemapOptions& o, OutputPlan& plan,
                     GazemapReport& rep) {
  const RoadLocator where(road);
  const RoadPhotos photos(where);
  const Frames frames = LoadFrames(o);
  CheckGazeTimes(gaze, *frames.clock, o);
  const std::vector<size_t> homes = FrameHomes(frames, where, o);
  const ScreenGeometry screen = MakeScreen(o, where.model(homes.front()).RenderCamera());
  const IvtResult ivt = Fixate(gaze, screen, o, rep);
  RoadMeshes meshes(road);
  RoadRun run{road, where, photos, meshes};
  const bool labels = boxes.empty() && photos.HasLabels();
  const std::vector<MappedFixation> mapped =
      MapOnRoad(ivt, frames, screen, homes, boxes, labels, run, o);
  rep.aoi_from = AoiFrom(boxes, labels, o);
  Tally(mapped, rep);
  const MappedScene scene{photos.views, photo,
                          [&](HeatmapPainter& painter) { PaintRoad(painter, run); }, frames};
  WriteOutputs(mapped, scene, o, plan, rep);
}

// Every file a road's outputs depend on: Graph.txt, FRAMES, GAZE, the boxes, and each fragment's
// model, mesh, fragment.json, depth maps (--visibility depth) and label images (without boxes).
std::vector<fs::path> RoadGazeInputs(const GazemapOptions& o, const Road& road) {
  std::vector<fs::path> inputs{road.GraphPath(), Road::PathFileOf(road.root())};
  for (const std::string& p : {o.frames, o.gaze, o.aoi_boxes})
    if (!p.empty()) inputs.emplace_back(p);
  for (const RoadFragment& f : road.fragments()) {
    const Workspace ws(f.dir);
    for (fs::path& p : ws.SparseModelFiles()) inputs.push_back(std::move(p));
    inputs.push_back(ws.MeshPath());
    inputs.push_back(Road::RecordPath(f.dir));
    for (const std::string& name : f.owned_images) {
      if (o.visibility == GazeVisibility::kDepth) inputs.push_back(ws.DepthPath(name));
      if (o.aoi_boxes.empty()) inputs.push_back(ws.LabelPath(name));
    }
  }
  return inputs;
}

// Asks the record which outputs of a workspace or road at `root` must be made (up to date when
// none), makes them, and writes the record with why they were remade.
void PlanAndMake(const GazemapOptions& o, const OptionTable& table, const fs::path& root,
                 std::vector<fs::path> inputs, const PhotoOf& photo, GazemapReport& rep,
                 const std::function<void(OutputPlan&)>& make) {
  Ledger ledger(RecordRoot(o, root), "gazemap", table, std::move(inputs), root);
  OutputPlan plan{ledger, o.force, {}, {}};
  if (!PlanOutputs(o, photo, plan)) {
    rep.up_to_date = true;
    return;
  }
  make(plan);
  ledger.Write();
  rep.why = ledger.Summary();
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
  t.Positional("WS", &o.workspace,
               "Workspace folder (sparse/, mesh.ply; depth/, labels/ used), or a road "
               "(ROAD/Graph.txt): streamed fragment by fragment")
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
  GazemapOptions resolved = o;
  const OptionTable table = DeclareOptions(resolved);
  if (Road::IsRoad(o.workspace)) {
    const Road road(o.workspace);
    const PhotoOf photo = RoadPhotoOf(road);
    PlanAndMake(o, table, road.root(), RoadGazeInputs(o, road), photo, rep,
                [&](OutputPlan& plan) { MakeRoadOutputs(gaze, road, boxes, photo, o, plan, rep); });
    return rep;
  }
  const Workspace ws(o.workspace);
  ws.Require("gazemap", {WsItem::kSparse, WsItem::kMesh});
  const Reconstruction rec = ReadColmapModel(ws.SparseDir().string());
  PlanAndMake(
      o, table, ws.root(), GazeInputs(o, ws, rec),
      [&](const std::string& image) { return ws.SourceImagePath(image); }, rep,
      [&](OutputPlan& plan) { MakeOutputs(gaze, rec, boxes, ws, o, plan, rep); });
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
