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

#include "image/image.h"
#include "mkroad/mkroad.h"

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
  double median_rel = 0, within1 = 0, within5 = 0, completeness = 0, conf_good = 0, conf_bad = 0;
  size_t compared = 0;
};

// Pixels with a depth in both: relative error statistics; completeness over the truth's surface
// pixels; mean confidence of the pixels within 1 % and of those off by more than 5 %.
Accuracy Score(const fs::path& ws, const std::string& prefix) {
  std::vector<double> rel;
  size_t truth_px = 0, n_good = 0, n_bad = 0;
  double c_good = 0, c_bad = 0;
  for (const auto& e : fs::directory_iterator(ws / "stereo")) {
    const std::string f = e.path().filename().string();
    if (f.rfind(prefix, 0) != 0 || f.find(".conf.") != std::string::npos) continue;
    const Image d = ReadImage(e.path().string());
    const Image c = ReadImage((ws / "stereo" / (e.path().stem().string() + ".conf.exr")).string());
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
  a.within1 = double(std::count_if(rel.begin(), rel.end(), [](double r) { return r <= 0.01; })) / double(rel.size());
  a.within5 = double(std::count_if(rel.begin(), rel.end(), [](double r) { return r <= 0.05; })) / double(rel.size());
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
  std::printf("[densify mkroad 320x96, %zu px] median rel %.4f, within 1 %% %.3f, within 5 %% %.3f, "
              "completeness %.3f, confidence %.2f (<=1 %%) vs %.2f (>5 %%), %.0f ms/image\n",
              a.compared, a.median_rel, a.within1, a.within5, a.completeness, a.conf_good, a.conf_bad,
              r.ms_per_image);
  EXPECT_LT(a.median_rel, 0.02);
  EXPECT_GT(a.within5, 0.80);
  EXPECT_GT(a.completeness, 0.40);
  EXPECT_GT(a.conf_good, a.conf_bad);  // the confidence ranks good depths above bad ones
}

}  // namespace
}  // namespace mvtm
