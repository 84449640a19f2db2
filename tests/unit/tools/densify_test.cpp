// densify on the mkroad fixture against its CPU ray-traced depth (truth/depth/NAME.exr, computed
// by code that shares nothing with libcore/stereo): accuracy, completeness and confidence, and the
// same workspace under a similarity transform giving the same maps up to the scale.
#include "densify.h"

#include <gtest/gtest.h>
#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>

#include "bakedepth.h"
#include "image/image.h"
#include "io/colmap_model.h"
#include "mkroad/mkroad.h"
#include "roadmesh.h"

namespace mvtm {
namespace {

namespace fs = std::filesystem;

fs::path Root() {
  static fs::path r = fs::temp_directory_path() / ("mvtm-densify-" + std::to_string(getpid()));
  return r;
}

void MakeRoad(const fs::path& out, double scale_origin_x) {
  fixture::MkroadOptions m;
  m.frames = 12;
  m.vehicles = 0;  // a static scene: stereo has no answer for moving objects
  m.out_dir = out.string();
  m.fullsize_frames = 0;
  m.offpath_every = 0;
  m.quiet = true;
  m.origin = Eigen::Vector3d(scale_origin_x, 0, 0);
  fixture::RunMkroad(m);
}

struct Accuracy {
  double median_rel = 0, within1 = 0, within2 = 0, within5 = 0, completeness = 0, conf_good = 0,
         conf_bad = 0;
  size_t compared = 0;
};

// Pixels with a depth in both: relative error statistics; completeness over the truth's surface
// pixels; mean confidence of the pixels within 1 % and of those off by more than 5 %.
Accuracy Score(const fs::path& ws, const std::string& prefix, const std::string& dir = "stereo") {
  std::vector<double> rel;
  size_t truth_px = 0, n_good = 0, n_bad = 0;
  double c_good = 0, c_bad = 0;
  for (const auto& e : fs::directory_iterator(ws / dir)) {
    const std::string f = e.path().filename().string();
    if (f.rfind(prefix, 0) != 0 || f.find(".conf.") != std::string::npos) continue;
    const Image d = ReadImage(e.path().string());
    const fs::path cp = ws / dir / (e.path().stem().string() + ".conf.exr");
    const Image c = fs::exists(cp) ? ReadImage(cp.string()) : Image(d.width, d.height, 1, 32, 1.f);
    const Image t = ReadImage((ws / "truth/depth" / f).string());
    EXPECT_EQ(d.width, t.width);
    for (size_t i = 0; i < t.data.size(); ++i) {
      if (!std::isfinite(t.data[i])) continue;
      ++truth_px;
      if (!std::isfinite(d.data[i])) continue;
      const double r = std::abs(d.data[i] / t.data[i] - 1);
      rel.push_back(r);
      if (r <= 0.01) c_good += c.data[i], ++n_good;
      if (r > 0.05) c_bad += c.data[i], ++n_bad;
    }
  }
  Accuracy a;
  a.compared = rel.size();
  if (rel.empty()) return a;
  a.completeness = double(rel.size()) / double(truth_px);
  a.within1 = double(std::count_if(rel.begin(), rel.end(), [](double r) { return r <= 0.01; })) /
              double(rel.size());
  a.within2 = double(std::count_if(rel.begin(), rel.end(), [](double r) { return r <= 0.02; })) /
              double(rel.size());
  a.within5 = double(std::count_if(rel.begin(), rel.end(), [](double r) { return r <= 0.05; })) /
              double(rel.size());
  std::nth_element(rel.begin(), rel.begin() + long(rel.size() / 2), rel.end());
  a.median_rel = rel[rel.size() / 2];
  a.conf_good = n_good ? c_good / double(n_good) : 0;
  a.conf_bad = n_bad ? c_bad / double(n_bad) : 0;
  return a;
}

DensifyReport Densify(const fs::path& ws) {
  DensifyOptions o;
  o.workspace = ws.string();
  o.scale = 1.0;  // the truth's resolution
  o.quiet = true;
  return RunDensify(o);
}

TEST(Densify, MkroadDepthAgainstRayTracedTruth) {
  const fs::path ws = Root() / "road";
  MakeRoad(ws, 0);
  const DensifyReport r = Densify(ws);
  EXPECT_EQ(r.written, 24u);
  EXPECT_EQ(r.no_neighbours, 0u);
  const Accuracy a = Score(ws, "");
  std::printf(
      "[densify mkroad 320x96, %zu px] median rel %.4f, within 1 %% %.3f, within 2 %% %.3f, within "
      "5 %% %.3f, completeness %.3f, confidence %.2f (<=1 %%) vs %.2f (>5 %%), %.0f ms/image\n",
      a.compared, a.median_rel, a.within1, a.within2, a.within5, a.completeness, a.conf_good,
      a.conf_bad, r.ms_per_image);
  // Measured at 320x96 (12 frames a pass): median 0.020, within 5 % 0.70, completeness 0.65
  // (0.033, 0.59 and 0.60 before the per-pixel refinement and the neighbours from the other
  // drive). Raw single-view stereo at this size is coarse (1 px is ~1.5 % of depth at 10 m);
  // fusion below is what the mesh is made of.
  EXPECT_LT(a.median_rel, 0.03);
  EXPECT_GT(a.within5, 0.62);
  EXPECT_GT(a.completeness, 0.60);
  EXPECT_GT(a.conf_good, a.conf_bad);  // the confidence ranks good depths above bad ones

  // roadmesh --dense (fused, closed by the corridor ground) against the corridor proxy alone,
  // both baked from the recorded poses and scored against the truth.
  auto bake = [&](bool dense, double walls_behind) {
    RoadMeshOptions m;
    m.workspace = ws.string();
    m.dense = dense;
    m.walls_behind = walls_behind;
    m.force = m.quiet = m.no_colours = true;
    RunRoadMesh(m);
    BakeDepthOptions b;
    b.workspace = ws.string();
    b.force = b.quiet = true;
    RunBakeDepth(b);
    return Score(ws, "", "depth");
  };
  const Accuracy corridor = bake(false, 0), fused = bake(true, -1), closed = bake(true, 20);
  for (const auto& [name, x] : {std::pair<const char*, Accuracy>{"corridor", corridor},
                                {"dense, no walls", fused},
                                {"dense, walls behind", closed}})
    std::printf(
        "[mesh %s] median rel %.4f, within 1 %% %.3f, within 2 %% %.3f, within 5 %% %.3f, surface "
        "on %.3f of truth pixels\n",
        name, x.median_rel, x.within1, x.within2, x.within5, x.completeness);
  // Where the fused surface exists it is nearer the truth than the corridor proxy (the numbers
  // measured with the strict consistency filter, before 4 Dec 2026)...
  EXPECT_GT(fused.within1, corridor.within1 + 0.03);  // measured 0.65 vs 0.59
  EXPECT_GT(fused.within5, corridor.within5 + 0.05);  // measured 0.86 vs 0.75
  EXPECT_GT(fused.completeness, 0.75);                // measured 0.80
  // ...and the corridor's walls behind it close the holes (they show through them only).
  EXPECT_GT(closed.completeness, 0.88);  // measured 0.91 (the corridor alone: 0.91)
}

TEST(Densify, AnImageWithoutSparsePointsSweepsOverItsNeighbours) {
  const fs::path ws = Root() / "nopoints";
  MakeRoad(ws, 0);
  // Image A_0005 loses every observation (and the tracks lose it): its sweep ranges must come
  // from its neighbours' points, and its depth must still agree with the truth.
  Reconstruction rec = ReadColmapModel((ws / "sparse").string());
  const ImageRecord* a5 = rec.FindImage("A_0005.png");
  ASSERT_NE(a5, nullptr);
  const uint32_t id = a5->id;
  for (auto& p : rec.images[id].points2D) p.point3D_id = kInvalidPoint3DId;
  for (auto& [pid, pt] : rec.points3D)
    pt.track.erase(std::remove_if(pt.track.begin(), pt.track.end(),
                                  [&](const TrackElement& e) { return e.image_id == id; }),
                   pt.track.end());
  WriteColmapText(rec, (ws / "sparse").string());
  DensifyOptions o;
  o.workspace = ws.string();
  o.scale = 1.0;
  o.frames = "5:6";  // A_0005 in name order
  o.quiet = true;
  ASSERT_EQ(RunDensify(o).written, 1u);
  const Accuracy a = Score(ws, "A_0005");
  std::printf("[densify, no points of its own] %zu px, median rel %.4f, completeness %.3f\n",
              a.compared, a.median_rel, a.completeness);
  EXPECT_GT(a.completeness, 0.3);
  EXPECT_LT(a.median_rel, 0.06);
}

}  // namespace
}  // namespace mvtm
