#include "densify.h"

#include <chrono>
#include <cmath>
#include <opencv2/imgproc.hpp>

#include "base/atomic_file.h"
#include "base/error.h"
#include "cli/progress.h"
#include "image/image.h"
#include "io/colmap_model.h"
#include "workspace/workspace.h"

namespace mvtm {

void DensifyOptions::Check() const {
  CheckWork();
  if (!(scale > 0 && scale <= 1)) throw UsageError("--scale: must be in (0, 1]");
  if (planes < 2 || planes > 512) throw UsageError("--planes: must be 2..512");
  if (no_ground && no_facade && no_fronto)
    throw UsageError("--no-ground, --no-facade, --no-fronto: keep one direction");
  neighbours.Check();
  sweep.Check();
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

Camera ScaledCamera(const Camera& c, double scale) {
  c.RequireUndistorted();
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
  std::vector<Camera> cameras;  // at --scale
  Eigen::Vector3d down, side;
};

DenseScene LoadDenseScene(const Workspace& ws, double scale) {
  DenseScene s;
  s.rec = ReadColmapModel(ws.SparseDir().string());
  s.images = s.rec.ImagesByName();
  for (const auto* im : s.images) {
    s.w2c.push_back(im->world_to_camera);
    s.cameras.push_back(ScaledCamera(s.rec.cameras.at(im->camera_id), scale));
  }
  DriveAxes(s.w2c, s.down, s.side);
  return s;
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

// Sweeps image i and writes its depth and confidence maps (atomically). Returns the valid share.
double DensifyOne(const DensifyOptions& o, const Workspace& ws, const DenseScene& s,
                  const StereoNeighbourFinder& finder, size_t i, DensifyReport& rep) {
  std::vector<Eigen::Vector3d> pts = PointsSeenBy(s.rec, *s.images[i]);
  const std::vector<size_t> nbs = finder.Select(i, pts);
  if (nbs.empty()) ++rep.no_neighbours;
  if (pts.size() < 3)  // an image with (almost) no sparse points sweeps over its neighbours' points
    for (size_t j : nbs)
      for (const auto& X : PointsSeenBy(s.rec, *s.images[j])) pts.push_back(X);
  StereoView ref{s.cameras[i], s.w2c[i],
                 LoadGrey(ws.ImagePath(s.images[i]->name), s.rec.cameras.at(s.images[i]->camera_id),
                          s.cameras[i])};
  std::vector<StereoView> views;
  for (size_t j : nbs)
    views.push_back({s.cameras[j], s.w2c[j],
                     LoadGrey(ws.ImagePath(s.images[j]->name),
                              s.rec.cameras.at(s.images[j]->camera_id), s.cameras[j])});
  const DepthMap dm = SweepDepth(ref, views, Families(o, s, i, pts), o.sweep);
  WriteImage(ws.StereoDepthPath(s.images[i]->name).string(), dm.depth);
  WriteImage(ws.StereoConfidencePath(s.images[i]->name).string(), dm.confidence);
  size_t valid = 0;
  for (float z : dm.depth.data) valid += std::isfinite(z);
  return dm.depth.data.empty() ? 0 : double(valid) / double(dm.depth.data.size());
}

}  // namespace

DensifyReport RunDensify(const DensifyOptions& o) {
  o.Check();
  Workspace ws(o.workspace);
  ws.Require("densify", {WsItem::kSparse, WsItem::kImages});
  const DenseScene s = LoadDenseScene(ws, o.scale);
  const std::vector<size_t> chosen = o.Select().Apply(s.images.size());
  DensifyReport rep;
  rep.selected = chosen.size();
  const std::vector<fs::path> inputs = ws.SparseModelFiles();
  std::vector<size_t> todo;
  for (size_t i : chosen) {
    const fs::path d = ws.StereoDepthPath(s.images[i]->name),
                   c = ws.StereoConfidencePath(s.images[i]->name);
    if (!o.force && IsUpToDate(d, inputs) && IsUpToDate(c, inputs))
      ++rep.skipped;
    else
      todo.push_back(i);
  }
  RemoveStaleTemporaries(ws.StereoDir());  // a killed run's leftovers, even when all is up to date
  if (todo.empty()) return rep;
  CreateFolder(ws.StereoDir());
  Progress bar("densify", todo.size(), o.quiet);
  double share = 0;
  const auto t0 = Clock::now();
  const StereoNeighbourFinder finder(s.w2c, s.cameras, o.neighbours);
  for (size_t i : todo) {
    share += DensifyOne(o, ws, s, finder, i, rep);
    ++rep.written;
    bar.Step();
  }
  rep.ms_per_image =
      std::chrono::duration<double, std::milli>(Clock::now() - t0).count() / double(rep.written);
  rep.valid_share = share / double(rep.written);
  nlohmann::json opts = {{"scale", o.scale},
                         {"planes", o.planes},
                         {"neighbours", o.neighbours.count},
                         {"window", o.sweep.window},
                         {"best_k", o.sweep.best_k},
                         {"min_score", o.sweep.min_score},
                         {"min_texture", o.sweep.min_texture},
                         {"min_margin", o.sweep.min_margin},
                         {"refine", o.sweep.refine},
                         {"no_ground", o.no_ground},
                         {"no_facade", o.no_facade},
                         {"no_fronto", o.no_fronto},
                         {"frames", o.frames},
                         {"shard", o.shard}};
  ws.WriteProvenance(o.ProvenanceName("densify"), opts, inputs);
  return rep;
}

}  // namespace mvtm
