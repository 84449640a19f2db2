// bakedepth and ptmrender on the mkroad fixture, scored against its CPU ray-traced truth with
// libcore/image's SSIM (equal to scikit-image's). The tables printed here are the numbers in
// the README and the issue notes.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <sstream>

#include "bakedepth.h"
#include "image/image.h"
#include "image/ssim.h"
#include "io/mesh_io.h"
#include "mkroad/mkroad.h"
#include "ptmrender.h"

namespace mvtm {
namespace {

namespace fs = std::filesystem;

fs::path Root() {
  static fs::path r = fs::temp_directory_path() / ("mvtm-ptm-truth-" + std::to_string(getpid()));
  return r;
}

class PtmTruth : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    fs::remove_all(Root());
    for (bool utm : {false, true}) {
      fixture::MkroadOptions o;
      o.frames = 12;
      o.out_dir = (Root() / (utm ? "utm" : "local")).string();
      o.fullsize_frames = 0;
      o.offpath_every = 3;
      o.quiet = true;
      if (utm) o.origin = Eigen::Vector3d(451000, 5410000, 120);
      fixture::RunMkroad(o);
      // The fixture's true vehicle masks, where segtrack would put its masks.
      fs::create_directories(fs::path(o.out_dir) / "masks");
      for (const auto& e : fs::directory_iterator(fs::path(o.out_dir) / "truth/masks"))
        fs::copy_file(e.path(), fs::path(o.out_dir) / "masks" / e.path().filename());
      BakeDepthOptions b;
      b.workspace = o.out_dir;
      b.quiet = true;
      RunBakeDepth(b);
    }
  }
  static void TearDownTestSuite() {
    if (!std::getenv("MVTM_KEEP")) fs::remove_all(Root());
  }

  static PtmRenderReport Render(const std::string& ws, const std::string& out,
                                const std::function<void(PtmRenderOptions&)>& set) {
    PtmRenderOptions o;
    o.workspace = (Root() / ws).string();
    o.outdir = (Root() / "renders" / out).string();
    o.quiet = true;
    o.force = true;
    set(o);
    std::ostringstream sink;
    PtmRenderReport rep = RunPtmRender(o, sink);
    // Every score below is over the frames on disk: none rendered must fail, not pass vacuously.
    EXPECT_GT(rep.frames, 0u) << out;
    EXPECT_EQ(rep.rendered, rep.frames) << out;
    return rep;
  }

  // SSIM of every frame in renders/OUT against TRUTH_DIR (same names).
  static std::vector<std::pair<std::string, double>> Score(const std::string& out,
                                                           const fs::path& truth) {
    std::vector<std::pair<std::string, double>> r;
    std::vector<fs::path> files;
    for (const auto& e : fs::directory_iterator(Root() / "renders" / out))
      if (e.is_regular_file()) files.push_back(e.path());
    std::sort(files.begin(), files.end());
    EXPECT_FALSE(files.empty()) << "no frame rendered into renders/" << out;
    SsimOptions so;
    for (const auto& f : files)
      r.emplace_back(f.filename().string(),
                     Ssim(ReadImage(f.string()), ReadImage((truth / f.filename()).string()), so));
    return r;
  }
  static double Mean(const std::vector<std::pair<std::string, double>>& v) {
    double s = 0;
    for (const auto& [n, x] : v) s += x;
    return v.empty() ? NAN : s / double(v.size());
  }
};

TEST_F(PtmTruth, BakedDepthMatchesRayTracedDepth) {
  for (const char* ws : {"local", "utm"}) {
    std::vector<double> rel;
    size_t disagree = 0, total = 0, inf_mismatch = 0;
    for (const auto& e : fs::directory_iterator(Root() / ws / "depth")) {
      Image ours = ReadImage(e.path().string());
      Image truth = ReadImage((Root() / ws / "truth/depth" / e.path().filename()).string());
      ASSERT_EQ(ours.width, truth.width);
      for (size_t i = 0; i < ours.data.size(); ++i) {
        ++total;
        bool a = std::isinf(ours.data[i]), b = std::isinf(truth.data[i]);
        if (a || b) {
          inf_mismatch += a != b;
          disagree += a != b;
          continue;
        }
        double r = std::abs(ours.data[i] - truth.data[i]) / truth.data[i];
        rel.push_back(r);
        disagree += r > 0.01;
      }
    }
    std::nth_element(rel.begin(), rel.begin() + rel.size() / 2, rel.end());
    double median = rel[rel.size() / 2];
    std::printf(
        "[bakedepth %s] %zu pixels: median |d - truth|/truth %.2e; %.3f %% disagree by > 1 %% "
        "(%zu surface/sky mismatches: silhouettes)\n",
        ws, total, median, 100.0 * disagree / total, inf_mismatch);
    EXPECT_LT(median, 1e-3);
    EXPECT_LT(double(disagree) / total, 0.02);  // silhouettes only
  }
  // The UTM-like workspace bakes the same depth as the one at the origin.
  double worst_median = 0;
  for (const auto& e : fs::directory_iterator(Root() / "local" / "depth")) {
    Image a = ReadImage(e.path().string()),
          b = ReadImage((Root() / "utm/depth" / e.path().filename()).string());
    std::vector<double> rel;
    for (size_t i = 0; i < a.data.size(); ++i)
      if (!std::isinf(a.data[i]) && !std::isinf(b.data[i]))
        rel.push_back(std::abs(a.data[i] - b.data[i]) / a.data[i]);
    std::nth_element(rel.begin(), rel.begin() + rel.size() / 2, rel.end());
    worst_median = std::max(worst_median, rel[rel.size() / 2]);
  }
  std::printf("[bakedepth utm vs local] worst per-image median relative difference %.2e\n",
              worst_median);
  EXPECT_LT(worst_median, 1e-3);
}

TEST_F(PtmTruth, SelfProjectionReproducesTheRecordedImage) {
  // The image itself as the only projector, unmasked: the recorded image comes back.
  Render("local", "self", [](PtmRenderOptions& o) { o.projectors = 1, o.no_masks = true; });
  auto s = Score("self", Root() / "local/images");
  double worst = 1;
  for (const auto& [n, v] : s) worst = std::min(worst, v);
  std::printf("[self-projection] %zu frames, worst SSIM %.9f\n", s.size(), worst);
  // Measured 1.000000000 on llvmpipe (texel centres hit exactly); 1e-6 leaves room for GPU
  // rounding.
  for (const auto& [n, v] : s) EXPECT_GE(v, 1 - 1e-6) << n;
}

TEST_F(PtmTruth, HeldOutPosesPtmBeatsVertexColoursOnEveryFrame) {
  Render("local", "heldout_vertex", [](PtmRenderOptions& o) { o.mode = PtmMode::kVertex; });
  Render("local", "heldout_ptm", [](PtmRenderOptions& o) { o.at_images = o.exclude_self = true; });
  auto v = Score("heldout_vertex", Root() / "local/truth/background");
  auto p = Score("heldout_ptm", Root() / "local/truth/background");
  ASSERT_EQ(v.size(), p.size());
  size_t wins = 0;
  for (size_t i = 0; i < v.size(); ++i) {
    wins += p[i].second > v[i].second;
    EXPECT_GT(p[i].second, v[i].second) << p[i].first;
  }
  std::printf(
      "[held-out, exclude-self, true masks] %zu frames: vertex %.4f, PTM %.4f mean SSIM; PTM wins "
      "%zu/%zu\n",
      v.size(), Mean(v), Mean(p), wins, v.size());
}

TEST_F(PtmTruth, OffPathConfigurationsTable) {
  struct Config {
    const char* name;
    std::function<void(PtmRenderOptions&)> set;
  };
  std::vector<Config> configs = {
      {"vertex", [](PtmRenderOptions& o) { o.mode = PtmMode::kVertex; }},
      {"ptm",
       [](PtmRenderOptions& o) {
         o.projectors = 1, o.no_occlusion = true, o.no_skybox = true, o.no_fill = true;
       }},
      {"+occlusion",
       [](PtmRenderOptions& o) { o.projectors = 1, o.no_skybox = true, o.no_fill = true; }},
      {"+several",
       [](PtmRenderOptions& o) {
         o.projectors = 4, o.no_blend = true, o.no_skybox = true, o.no_fill = true;
       }},
      {"+blend",
       [](PtmRenderOptions& o) { o.projectors = 4, o.no_skybox = true, o.no_fill = true; }},
      {"+skybox",
       [](PtmRenderOptions& o) { o.projectors = 4, o.no_fill = true, o.sky_distance = 0; }},
      {"+sky far", [](PtmRenderOptions& o) { o.projectors = 4, o.no_fill = true; }},
      {"+fill", [](PtmRenderOptions& o) { o.projectors = 4; }},
  };
  std::printf("[off-path] mean SSIM against ray-traced truth\n%-12s", "variant");
  for (const auto& c : configs) std::printf(" %10s", c.name);
  std::printf("\n");
  std::vector<double> sum(configs.size(), 0);
  int variants = 0;
  for (const char* var : {"lane_left", "lane_right", "yaw_left", "yaw_right"}) {
    std::printf("%-12s", var);
    fs::path truth = Root() / "local/truth/offpath" / var;
    for (size_t c = 0; c < configs.size(); ++c) {
      std::string out = std::string(var) + "_" + std::to_string(c);
      Render("local", out, [&](PtmRenderOptions& o) {
        o.poses = (truth / "sparse/images.txt").string();
        configs[c].set(o);
      });
      double m = Mean(Score(out, truth / "images"));
      sum[c] += m;
      std::printf(" %10.4f", m);
    }
    std::printf("\n");
    ++variants;
  }
  std::printf("%-12s", "mean");
  for (size_t c = 0; c < configs.size(); ++c) std::printf(" %10.4f", sum[c] / variants);
  std::printf("\n");
  // No added effect lowers the mean, except that blending may cost a little here: on the
  // fixture's exact mesh the nearest projector is already right, and a blend resamples several
  // (measured: 0.7783 first projector, 0.7741 blended at power 2), while on meshes built from the
  // photos it gains (mkroad's road build: lanes 0.631/0.642 → 0.634/0.664; KITTI 01's right
  // camera: 0.729 → 0.747).
  for (size_t c = 1; c < configs.size(); ++c)
    EXPECT_GE(sum[c], sum[c - 1] - (std::string(configs[c].name) == "+blend" ? 0.04 : 1e-9))
        << configs[c].name;
  EXPECT_GT(sum[1], sum[0]);  // PTM beats vertex colours
}

// Issue 19's "no black, ever": a mesh with holes (every 9th triangle removed, as a mesh built
// from photos has them) seen 1.5 m beside the path. Through a hole the render sees nothing, and
// in that direction the projectors see the surface behind it, not sky: without the fill those
// pixels are the constant black background. With it, not a single pixel is black where the
// ray-traced truth is not.
TEST_F(PtmTruth, NoBlackPixelBesideThePathOnAMeshWithHoles) {
  const fs::path local = Root() / "local", holed = Root() / "holed";
  fs::create_directories(holed);
  for (const char* item : {"sparse", "images", "masks"})
    fs::copy(local / item, holed / item, fs::copy_options::recursive);
  Mesh mesh = ReadMesh((local / "mesh.ply").string());
  std::vector<std::array<uint32_t, 3>> kept;
  for (size_t f = 0; f < mesh.faces.size(); ++f)
    if (f % 9 != 4) kept.push_back(mesh.faces[f]);
  mesh.faces = kept;
  WriteMesh((holed / "mesh.ply").string(), mesh);
  BakeDepthOptions b;
  b.workspace = holed.string();
  b.quiet = true;
  RunBakeDepth(b);
  const fs::path truth = local / "truth/offpath/lane_left";
  auto black = [](const Image& im, size_t p) {
    for (int c = 0; c < std::min(im.channels, 3); ++c)
      if (im.data[p * im.channels + c] > 2) return false;
    return true;
  };
  auto count = [&](const std::string& out) {
    size_t n = 0, frames = 0;
    for (const auto& e : fs::directory_iterator(Root() / "renders" / out)) {
      if (!e.is_regular_file()) continue;
      const Image r = ReadImage(e.path().string());
      const Image t = ReadImage((truth / "images" / e.path().filename()).string());
      for (size_t p = 0; p < r.pixels(); ++p) n += black(r, p) && !black(t, p);
      ++frames;
    }
    EXPECT_GT(frames, 0u);
    return n;
  };
  for (bool fill : {false, true})
    Render("holed", fill ? "holed_fill" : "holed_nofill", [&](PtmRenderOptions& o) {
      o.poses = (truth / "sparse/images.txt").string();
      o.no_fill = !fill;
    });
  const size_t without = count("holed_nofill"), with = count("holed_fill");
  std::printf(
      "[holed mesh, 1.5 m left] black pixels where the truth has none: %zu without the "
      "fill, %zu with it\n",
      without, with);
  EXPECT_GT(without, 100u);  // the scene exercises the fill
  EXPECT_EQ(with, 0u);
}

TEST_F(PtmTruth, UtmSceneRendersLikeTheOrigin) {
  Render("local", "origin_lane", [&](PtmRenderOptions& o) { o.lateral = 1.5; });
  Render("utm", "utm_lane", [&](PtmRenderOptions& o) { o.lateral = 1.5; });
  auto s = Score("utm_lane", Root() / "renders/origin_lane");
  double worst = 1;
  size_t differ = 0, pixels = 0;
  for (const auto& [n, v] : s) {
    worst = std::min(worst, v);
    Image a = ReadImage((Root() / "renders/origin_lane" / n).string()),
          b = ReadImage((Root() / "renders/utm_lane" / n).string());
    for (size_t p = 0; p < a.pixels(); ++p) {
      bool d = false;
      for (int c = 0; c < a.channels; ++c)
        d |= a.data[p * a.channels + c] != b.data[p * b.channels + c];
      differ += d;
    }
    pixels += a.pixels();
  }
  std::printf(
      "[utm vs origin] %zu frames rendered 1.5 m left: mean SSIM %.6f, worst %.6f; %.4f %% of "
      "pixels differ\n",
      s.size(), Mean(s), worst, 100.0 * differ / pixels);
  // The two scenes differ only in the last bits of poses and vertices (rounding of x + origin in
  // double), which can flip a pixel on a silhouette or at the occlusion threshold; at 320×96 ten
  // such pixels cost 0.001 SSIM in one frame. A float32 pipeline at UTM would be off by decimetres.
  EXPECT_GE(Mean(s), 0.999);
  EXPECT_GE(worst, 0.995);
  EXPECT_LT(double(differ) / pixels, 1e-3);
}

}  // namespace
}  // namespace mvtm
