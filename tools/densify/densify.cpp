#include "densify.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <opencv2/imgproc.hpp>

#include "base/atomic_file.h"
#include "base/error.h"
#include "cli/progress.h"
#include "image/image.h"
#include "io/colmap_model.h"
#include "run/ledger.h"
#include "workspace/workspace.h"

namespace mvtm {

OptionTable DeclareOptions(DensifyOptions& o) {
  OptionTable t("densify");
  t.Positional("WS", &o.workspace, "Workspace folder (sparse/ with points, images/)").Dir();
  t.Real("--scale", &o.scale, "Depth map size relative to the image (0..1; 0: from --map-focal)")
      .Range(0, 1)
      .Alternative("0.5");
  t.Real("--map-focal", &o.map_focal,
         "With --scale 0: each map's focal length in pixels (16..100000), at most its image's "
         "(360: a 7-pixel window spans 0.16 m at 8 m); ignored when --scale is given")
      .Range(16, 100000);
  t.Integer("--planes", &o.planes, "Planes per sweep direction (2..512)").Range(2, 512);
  t.Flag("--no-ground", &o.no_ground, "Leave out the ground-parallel sweep");
  t.Flag("--no-facade", &o.no_facade, "Leave out the facade-parallel sweep");
  t.Flag("--no-fronto", &o.no_fronto, "Leave out the fronto-parallel sweep");
  t.Integer("--neighbours", &o.neighbours.count, "Neighbour images per reference (1..16)")
      .Range(1, 16);
  t.Real("--min-baseline", &o.neighbours.min_baseline,
         "Smallest baseline, as a fraction of the median camera spacing")
      .Range(0, 10, false, true);
  t.Real("--max-angle", &o.neighbours.max_angle_deg,
         "Largest angle between viewing directions, degrees")
      .Range(0, 90, true);
  t.Real("--min-coverage", &o.neighbours.min_coverage,
         "Share of the reference's sparse points a neighbour must see")
      .Range(0, 1);
  t.Integer("--window", &o.sweep.window, "ZNCC window side in pixels (odd, 3..31)")
      .Range(3, 31)
      .Check([&o] {
        if (o.sweep.window % 2 == 0) throw UsageError("--window: must be odd, 3..31");
      });
  t.Integer("--best-k", &o.sweep.best_k, "Neighbours aggregated per pixel: the best K of N")
      .AtLeast(1);
  t.Real("--min-score", &o.sweep.min_score, "Aggregated ZNCC below which a pixel gets no depth")
      .Range(-1, 1);
  t.Real("--min-margin", &o.sweep.min_margin,
         "Best score minus the mean over planes below which a match is ambiguous")
      .Range(0, 2);
  t.Integer("--refine", &o.sweep.refine,
            "Sub-steps per plane spacing of the per-pixel refinement of the best plane "
            "(0..64; 0: a parabola through the planes only)")
      .Range(0, 64);
  t.Real("--min-texture", &o.sweep.min_texture,
         "Grey standard deviation (0..255) below which a window is textureless")
      .AtLeast(0);
  DeclareWorkOptions(t, o, "images", "in name order",
                     "Recompute maps even when they are up to date");
  return t;
}

void DensifyOptions::Check() const {
  CheckDeclared(*this);
  if (no_ground && no_facade && no_fronto)
    throw UsageError("--no-ground, --no-facade, --no-fronto: keep one direction");
}

namespace {

using Clock = std::chrono::steady_clock;

// The image (of its model camera `full`'s size) as grey float on the 0..255 scale, resized to
// the working camera `cam`'s size.
cv::Mat LoadGrey(const fs::path& path, const Camera& full, const Camera& cam) {
  Image colour = ReadImage(path.string());
  RequireImageSize(colour, path.string(), full.width, full.height);
  const Image im = ToGrey(colour);
  cv::Mat g;  // a copy: the Image's buffer dies with it
  cv::Mat(im.height, im.width, CV_32F, const_cast<float*>(im.data.data()))
      .convertTo(g, CV_32F, 255.0 / im.MaxValue());
  if (g.cols != int(cam.width) || g.rows != int(cam.height))
    cv::resize(g, g, cv::Size(int(cam.width), int(cam.height)), 0, 0, cv::INTER_AREA);
  return g;
}

// The scale of an image's maps: --scale, or with --scale 0 the scale that gives the maps a
// focal length of --map-focal pixels (the larger of fx and fy), never above the image's size.
double MapScale(const Camera& c, const DensifyOptions& o) {
  return o.scale > 0 ? o.scale : std::min(1.0, o.map_focal / std::max(c.fx(), c.fy()));
}

// The camera of an image's maps (MapScale, sizes rounded).
Camera ScaledCamera(const Camera& c, const DensifyOptions& o) {
  c.RequireUndistorted();
  const double scale = MapScale(c, o);
  if (scale == 1.0) return c;
  return c.Scaled(std::max<uint64_t>(1, uint64_t(std::lround(double(c.width) * scale))),
                  std::max<uint64_t>(1, uint64_t(std::lround(double(c.height) * scale))));
}

// The 3-D points an image observes (its points2D with a track).
std::vector<Eigen::Vector3d> PointsSeenBy(const Reconstruction& rec, const ImageRecord& im) {
  std::vector<Eigen::Vector3d> pts;
  for (const auto& p : im.points2D)
    if (p.point3D_id != kInvalidPoint3DId) pts.push_back(rec.points3D.at(p.point3D_id).xyz);
  return pts;
}

struct DenseScene {
  Reconstruction rec;
  std::vector<const ImageRecord*> images;
  std::vector<Rigid3d> w2c;
  std::vector<Camera> cameras;  // of the maps (ScaledCamera)
  Eigen::Vector3d down, side;
};

DenseScene LoadDenseScene(const Workspace& ws, const DensifyOptions& o) {
  DenseScene s;
  s.rec = ReadColmapModel(ws.SparseDir().string());
  s.images = s.rec.ImagesByName();
  for (const auto* im : s.images) {
    s.w2c.push_back(im->world_to_camera);
    s.cameras.push_back(ScaledCamera(s.rec.cameras.at(im->camera_id), o));
  }
  DriveAxes(s.w2c, s.down, s.side);
  return s;
}

// Each model camera's map scale and size, what --scale (0: from --map-focal) comes to for it:
// the record's entry of the run that made a map says it, since the options alone do not.
nlohmann::json MapSizes(const DensifyOptions& o, const DenseScene& s) {
  nlohmann::json j = nlohmann::json::object();
  for (size_t i = 0; i < s.images.size(); ++i) {
    const std::string key = std::to_string(s.images[i]->camera_id);
    if (j.contains(key)) continue;  // one entry per camera, not per image
    j[key] = {{"scale", MapScale(s.rec.cameras.at(s.images[i]->camera_id), o)},
              {"width", s.cameras[i].width},
              {"height", s.cameras[i].height}};
  }
  return j;
}

std::vector<SweepFamily> Families(const DensifyOptions& o, const DenseScene& s, size_t i,
                                  const std::vector<Eigen::Vector3d>& pts) {
  std::vector<SweepFamily> out;
  for (auto& f : SweepFamiliesFor(s.w2c[i], pts, s.down, s.side, o.planes))
    if (!(f.name == "fronto" && o.no_fronto) && !(f.name == "ground" && o.no_ground) &&
        !(f.name == "facade" && o.no_facade))
      out.push_back(std::move(f));
  return out;
}

// One image's work: its index, its neighbours, and the files its maps are made from beyond the
// model (its own image and its neighbours').
struct DenseJob {
  size_t i = 0;
  std::vector<size_t> neighbours;
  std::vector<fs::path> in;
};

// Sweeps image job.i and writes its depth and confidence maps (atomically), each recorded in the
// ledger once in place. Returns the valid share.
double DensifyOne(const DensifyOptions& o, const Workspace& ws, const DenseScene& s,
                  const DenseJob& job, Ledger& ledger) {
  const size_t i = job.i;
  std::vector<Eigen::Vector3d> pts = PointsSeenBy(s.rec, *s.images[i]);
  if (pts.size() < 3)  // an image with (almost) no sparse points sweeps over its neighbours' points
    for (size_t j : job.neighbours)
      for (const auto& X : PointsSeenBy(s.rec, *s.images[j])) pts.push_back(X);
  StereoView ref{s.cameras[i], s.w2c[i],
                 LoadGrey(ws.ImagePath(s.images[i]->name), s.rec.cameras.at(s.images[i]->camera_id),
                          s.cameras[i])};
  std::vector<StereoView> views;
  for (size_t j : job.neighbours)
    views.push_back({s.cameras[j], s.w2c[j],
                     LoadGrey(ws.ImagePath(s.images[j]->name),
                              s.rec.cameras.at(s.images[j]->camera_id), s.cameras[j])});
  const DepthMap dm = SweepDepth(ref, views, Families(o, s, i, pts), o.sweep);
  const fs::path depth = ws.StereoDepthPath(s.images[i]->name),
                 confidence = ws.StereoConfidencePath(s.images[i]->name);
  // One step: a kill between the two renames never leaves a new map beside an old confidence
  // for a reader (each reads the pair under LockForReading of stereo/).
  WriteImagesTogether({{depth.string(), &dm.depth}, {confidence.string(), &dm.confidence}});
  ledger.Done(depth, job.in);
  ledger.Done(confidence, job.in);
  size_t valid = 0;
  for (float z : dm.depth.data) valid += std::isfinite(z);
  return dm.depth.data.empty() ? 0 : double(valid) / double(dm.depth.data.size());
}

// The selected images whose maps are not both up to date, with their neighbours (chosen among
// all images of the model).
std::vector<DenseJob> StaleJobs(const DensifyOptions& o, const Workspace& ws, const DenseScene& s,
                                const std::vector<size_t>& chosen, Ledger& ledger,
                                DensifyReport& rep) {
  const StereoNeighbourFinder finder(s.w2c, s.cameras, o.neighbours);
  std::vector<DenseJob> todo;
  for (size_t i : chosen) {
    DenseJob job;
    job.i = i;
    job.neighbours = finder.Select(i, PointsSeenBy(s.rec, *s.images[i]));
    job.in.push_back(ws.ImagePath(s.images[i]->name));
    for (size_t j : job.neighbours) job.in.push_back(ws.ImagePath(s.images[j]->name));
    const std::string& name = s.images[i]->name;
    // Each map is asked (so both count in the summary); either stale redoes both.
    bool stale = !ledger.Stale(ws.StereoDepthPath(name), job.in, o.force).empty();
    stale = !ledger.Stale(ws.StereoConfidencePath(name), job.in, o.force).empty() || stale;
    if (stale)
      todo.push_back(std::move(job));
    else
      ++rep.skipped;
  }
  return todo;
}

}  // namespace

DensifyReport RunDensify(const DensifyOptions& o) {
  o.Check();
  Workspace ws(o.workspace);
  ws.Require("densify", {WsItem::kSparse, WsItem::kImages});
  const DenseScene s = LoadDenseScene(ws, o);
  const std::vector<size_t> chosen = o.Select().Apply(s.images.size());
  DensifyReport rep;
  rep.selected = chosen.size();
  DensifyOptions resolved = o;
  const OptionTable table = DeclareOptions(resolved);
  // The maps are inside the workspace: its record, provenance/densify.json (a shard's own).
  Ledger ledger(ws.root(), o.ProvenanceName("densify"), table, ws.SparseModelFiles(), ws.root());
  const std::vector<DenseJob> todo = StaleJobs(o, ws, s, chosen, ledger, rep);
  rep.why = ledger.Summary();
  RemoveStaleTemporaries(ws.StereoDir());  // a killed run's leftovers, even when all is up to date
  if (todo.empty()) return rep;
  ledger.NoteRun("map_sizes", MapSizes(o, s));
  CreateFolder(ws.StereoDir());
  Progress bar("densify", todo.size(), o.quiet);
  double share = 0;
  const auto t0 = Clock::now();
  for (const DenseJob& job : todo) {
    if (job.neighbours.empty()) ++rep.no_neighbours;
    share += DensifyOne(o, ws, s, job, ledger);
    ++rep.written;
    bar.Step();
  }
  rep.ms_per_image =
      std::chrono::duration<double, std::milli>(Clock::now() - t0).count() / double(rep.written);
  rep.valid_share = share / double(rep.written);
  ledger.Write();
  return rep;
}

}  // namespace mvtm
