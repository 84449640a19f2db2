// inpaint3d on the mkroad fixture: the pixels under the true vehicle masks of pass A, scored
// against the ray-traced background (truth/background, no vehicles) with libcore/image's SSIM
// inside the masks; then the thesis's Figure 5.11 comparison with ptmrender at held-out poses.
#include "inpaint3d.h"

#include <gtest/gtest.h>
#include <unistd.h>

#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <iterator>
#include <sstream>

#include "bakedepth.h"
#include "image/image.h"
#include "image/ssim.h"
#include "mkroad/mkroad.h"
#include "pickview.h"
#include "ptmrender.h"

namespace mvtm {
namespace {

namespace fs = std::filesystem;

constexpr int kFrames = 12;

fs::path Root() {
  static fs::path r = fs::temp_directory_path() / ("mvtm-inpaint3d-" + std::to_string(getpid()));
  return r;
}
fs::path Ws() { return Root() / "ws"; }

std::string Bytes(const fs::path& p) {
  std::ifstream f(p, std::ios::binary);
  return std::string(std::istreambuf_iterator<char>(f), {});
}

class Inpaint3dFixture : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    fs::remove_all(Root());
    fixture::MkroadOptions m;
    m.frames = kFrames;
    m.out_dir = Ws().string();
    m.fullsize_frames = 0;
    m.offpath_every = 0;
    m.quiet = true;
    fixture::RunMkroad(m);
    fs::create_directories(Ws() / "masks");
    for (const auto& e : fs::directory_iterator(Ws() / "truth/masks"))
      fs::copy_file(e.path(), Ws() / "masks" / e.path().filename());
    BakeDepthOptions b;
    b.workspace = Ws().string();
    b.quiet = true;
    RunBakeDepth(b);
    PickViewOptions p;
    p.workspace = Ws().string();
    p.partners = true;
    p.quiet = true;
    std::ostringstream sink;
    RunPickView(p, sink, std::cin);
  }
  static void TearDownTestSuite() {
    if (!std::getenv("MVTM_KEEP")) fs::remove_all(Root());
  }

  static Inpaint3dReport Inpaint(const std::string& method) {
    Inpaint3dOptions o;
    o.workspace = Ws().string();
    for (const auto& [e, name] : kInpaintMethods)
      if (name == method) o.method = e;
    o.force = true;
    o.quiet = true;
    return RunInpaint3d(o);
  }

  // Mean over pass A images with a non-empty mask of SSIM inside the mask against the truth.
  static double MaskedSsim(const fs::path& dir) {
    double sum = 0;
    int n = 0;
    SsimOptions so;
    for (int i = 0; i < kFrames; ++i) {
      char name[32];
      std::snprintf(name, sizeof name, "A_%04d.png", i);
      Image mask = ReadImage((Ws() / "masks" / name).string());
      double s = Ssim(ReadImage((dir / name).string()),
                      ReadImage((Ws() / "truth/background" / name).string()), so, &mask);
      if (std::isnan(s)) continue;  // empty mask (or masked pixels only in the border strip)
      sum += s;
      ++n;
    }
    return n ? sum / n : NAN;
  }
};

TEST_F(Inpaint3dFixture, ThreeDBeatsOpenCvInsideTheMasks) {
  std::printf(
      "[inpaint3d, mkroad %d frames/pass, true masks] mean SSIM inside the masks against "
      "truth/background\n",
      kFrames);
  double recorded = MaskedSsim(Ws() / "images");
  std::printf("  %-10s %.4f\n", "recorded", recorded);
  std::map<std::string, double> s;
  for (const char* m : {"telea", "ns", "patch2d", "3d"}) {
    Inpaint3dReport r = Inpaint(m);
    s[m] = MaskedSsim(Ws() / "textures");
    std::printf("  %-10s %.4f   (%zu inpainted, %zu copied; %.1f ms/image)\n", m, s[m], r.inpainted,
                r.copied, r.ms / double(r.inpainted + r.copied));
    EXPECT_GT(r.inpainted, 0u);
    // Every masked pixel is accounted for by exactly one provenance.
    EXPECT_GT(r.masked_pixels, 0u);
    EXPECT_EQ(r.from_partners + r.from_sky + r.from_vertex + r.from_background + r.from_2d,
              r.masked_pixels)
        << m;
    const std::string method = m;
    if (method == "telea" || method == "ns") {
      EXPECT_EQ(r.from_2d, r.masked_pixels);
    }
    if (method == "3d") {
      EXPECT_GT(r.from_partners, r.masked_pixels / 2);
    }
  }
  EXPECT_GT(s["3d"], s["telea"]);
  EXPECT_GT(s["3d"], s["ns"]);
  EXPECT_GT(s["3d"], recorded);
}

TEST_F(Inpaint3dFixture, OutsideTheMaskNothingChanges) {
  Inpaint3dOptions o;
  o.workspace = Ws().string();
  o.quiet = true;
  o.force = true;
  o.dilate = 2;
  RunInpaint3d(o);
  size_t checked = 0, changed_inside = 0;
  for (const auto& e : fs::directory_iterator(Ws() / "images")) {
    const std::string name = e.path().filename().string();
    fs::path tex = Ws() / "textures" / name, mp = Ws() / "masks" / name;
    ASSERT_TRUE(fs::exists(tex)) << name;
    ASSERT_TRUE(fs::exists(Ws() / "textures/provenance" / name)) << name;
    if (!fs::exists(mp)) {
      EXPECT_EQ(Bytes(tex), Bytes(e.path()))
          << name << ": an unmasked image is copied byte for byte";
      continue;
    }
    Image a = ReadImage(e.path().string()), b = ReadImage(tex.string()), m = ReadImage(mp.string());
    Image pv = ReadImage((Ws() / "textures/provenance" / name).string());
    ASSERT_EQ(a.channels, b.channels);
    ASSERT_EQ(a.bits, b.bits);
    for (int y = 0; y < a.height; ++y)
      for (int x = 0; x < a.width; ++x) {
        // Near the mask (within the dilation radius) pixels may change; elsewhere never.
        bool near = false;
        for (int dy = -2; dy <= 2 && !near; ++dy)
          for (int dx = -2; dx <= 2 && !near; ++dx) {
            int u = x + dx, v = y + dy;
            near = u >= 0 && v >= 0 && u < a.width && v < a.height && m.at(u, v) != 0;
          }
        if (m.at(x, y) != 0) {
          EXPECT_NE(pv.at(x, y), 0.f) << name;
        }
        if (near) {
          for (int c = 0; c < a.channels; ++c) changed_inside += a.at(x, y, c) != b.at(x, y, c);
          continue;
        }
        ++checked;
        EXPECT_EQ(pv.at(x, y), 0.f) << name << " " << x << "," << y;
        for (int c = 0; c < a.channels; ++c)
          ASSERT_EQ(a.at(x, y, c), b.at(x, y, c)) << name << " " << x << "," << y;
      }
  }
  std::printf("[outside the masks] %zu pixels unchanged; %zu samples changed under the masks\n",
              checked, changed_inside);
  EXPECT_GT(checked, 0u);
  EXPECT_GT(changed_inside, 0u);
}

TEST_F(Inpaint3dFixture, Figure511PtmInpaintingSkybox) {
  // Thesis Fig. 5.11 at held-out pass A poses (each image never projects onto its own pose).
  Inpaint("3d");
  auto render = [&](const std::string& out, bool skybox) {
    PtmRenderOptions o;
    o.workspace = Ws().string();
    o.outdir = (Root() / "renders" / out).string();
    o.at_images = o.exclude_self = true;
    o.frames = "0:" + std::to_string(kFrames);  // pass A (names sort A before B)
    o.no_masks = true;  // vehicles are projected unless textures/ removed them
    o.no_skybox = !skybox;
    o.quiet = o.force = true;
    std::ostringstream sink;
    RunPtmRender(o, sink);
  };
  auto frame = [&](const std::string& out, const char* name) {
    return ReadImage((Root() / "renders" / out / name).string());
  };
  // Whole frames, and only the pixels the inpainted textures changed (where (a) and (b) differ).
  const char* outs[3] = {"ptm", "inpainted", "inpainted_sky"};
  double whole[3] = {0, 0, 0}, changed[3] = {0, 0, 0};
  int n_changed = 0;
  size_t changed_pixels = 0;
  SsimOptions so;
  fs::rename(Ws() / "textures", Ws() / "textures.off");
  render("ptm", false);
  fs::rename(Ws() / "textures.off", Ws() / "textures");
  render("inpainted", false);
  render("inpainted_sky", true);
  for (int i = 0; i < kFrames; ++i) {
    char name[32];
    std::snprintf(name, sizeof name, "A_%04d.png", i);
    Image truth = ReadImage((Ws() / "truth/background" / name).string());
    Image a = frame("ptm", name), b = frame("inpainted", name);
    Image diff(a.width, a.height, 1, 8);
    bool any = false;
    for (int y = 0; y < a.height; ++y)
      for (int x = 0; x < a.width; ++x)
        for (int c = 0; c < a.channels; ++c)
          if (a.at(x, y, c) != b.at(x, y, c)) diff.at(x, y) = 255, any = true;
    for (int k = 0; k < 3; ++k) whole[k] += Ssim(frame(outs[k], name), truth, so) / kFrames;
    if (!any) continue;
    double v[3];
    for (int k = 0; k < 3; ++k) v[k] = Ssim(frame(outs[k], name), truth, so, &diff);
    if (std::isnan(v[0])) continue;
    for (int k = 0; k < 3; ++k) changed[k] += v[k];
    for (float d : diff.data) changed_pixels += d != 0;
    ++n_changed;
  }
  for (double& v : changed) v /= n_changed;
  std::printf(
      "[Fig. 5.11] ptmrender at held-out pass A poses, mean SSIM against truth/background\n"
      "  %-34s %12s %22s\n",
      "", "whole frame", "pixels inpainting changed");
  const char* label[3] = {"PTM (vehicles projected)", "PTM with inpainting",
                          "PTM with inpainting and skybox"};
  for (int k = 0; k < 3; ++k)
    std::printf("  %-34s %12.4f %22.4f\n", label[k], whole[k], changed[k]);
  std::printf("  (%zu changed pixels in %d of %d frames)\n", changed_pixels, n_changed, kFrames);
  ASSERT_GT(n_changed, 0);
  EXPECT_GT(changed[1], changed[0]);
  EXPECT_GE(whole[1], whole[0] - 1e-4);
  EXPECT_GT(whole[2], whole[1]);
}

}  // namespace
}  // namespace mvtm
