// orb2colmap at scale: 10^5 frames interpolated from 10^4 keyframes and written as a COLMAP model.
//
// Prints one table. Each stage is timed (best of --repeat runs) next to a baseline measured in the
// same run on the same machine, so the figures survive a noisy shared host:
//   interpolate   SLERP + linear centre for every frame      vs  Eigen's own Quaterniond::slerp
//   write text    our images.txt writer                      vs  `colmap model_converter` TXT→TXT
//   write binary  our images.bin writer                      vs  `colmap model_converter` BIN→BIN
//   read text     our images.txt reader                      (same model_converter baseline)
// usage: bench_orb2colmap [--frames N] [--repeat R] [--short]
#include <unistd.h>

#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <functional>
#include <random>
#include <string>

#include "bench_util.h"
#include "geometry/interpolate.h"
#include "io/colmap_model.h"

using namespace mvtm;
namespace fs = std::filesystem;

using bench::BestOf;

int main(int argc, char** argv) {
  size_t frames = 100000;
  int repeat = 3;
  for (int i = 1; i < argc; ++i) {
    std::string a = argv[i];
    if (a == "--frames" && i + 1 < argc)
      frames = std::stoul(argv[++i]);
    else if (a == "--repeat" && i + 1 < argc)
      repeat = std::stoi(argv[++i]);
    else if (a == "--short")
      frames = 2000, repeat = 1;
  }
  // A winding road: keyframes every 10th frame.
  std::mt19937 g(7);
  std::normal_distribution<double> nd(0, 0.01);
  std::vector<StampedPose> keys;
  for (size_t i = 0; i < frames; i += 10) {
    double s = static_cast<double>(i) * 0.1;
    Eigen::Quaterniond q(Eigen::AngleAxisd(0.3 * std::sin(s * 0.05), Eigen::Vector3d::UnitY()) *
                         Eigen::AngleAxisd(nd(g), Eigen::Vector3d::UnitX()));
    keys.push_back({s, Rigid3d(q, Eigen::Vector3d(100 * std::sin(s * 0.01), nd(g), s)), 0});
  }
  std::vector<double> times(frames);
  for (size_t i = 0; i < frames; ++i) times[i] = static_cast<double>(i) * 0.01;
  double end = keys.back().time;

  Reconstruction model;
  Camera cam = ParseCameraSpec("PINHOLE 1241 376 718.856 718.856 607.1928 185.2157");
  model.cameras[1] = cam;
  double t_interp = BestOf(repeat, [&] {
    model.images.clear();
    for (size_t i = 0; i < frames; ++i) {
      auto p = InterpolateCameraToWorld(keys, std::min(times[i], end), Outside::kClamp);
      ImageRecord im;
      im.id = static_cast<uint32_t>(i + 1);
      im.camera_id = 1;
      im.name = std::to_string(i) + ".png";
      im.world_to_camera = p->Inverse();
      model.images.emplace(im.id, std::move(im));
    }
  });
  volatile double sink = 0;
  double t_eigen = BestOf(repeat, [&] {
    for (size_t i = 0; i < frames; ++i) {
      size_t k = std::min(i / 10, keys.size() - 2);
      sink = sink + keys[k].pose.q.slerp(0.5, keys[k + 1].pose.q).w();
    }
  });
  fs::path dir = fs::temp_directory_path() / ("mvtm-bench-o2c-" + std::to_string(getpid()));
  fs::create_directories(dir / "txt");
  fs::create_directories(dir / "bin");
  double t_wtxt = BestOf(repeat, [&] { WriteColmapText(model, (dir / "txt").string()); });
  double t_wbin = BestOf(repeat, [&] { WriteColmapBinary(model, (dir / "bin").string()); });
  double t_rtxt = BestOf(repeat, [&] { ReadColmapText((dir / "txt").string()); });
  double t_rbin = BestOf(repeat, [&] { ReadColmapBinary((dir / "bin").string()); });
  bool have_colmap = std::system("command -v colmap >/dev/null 2>&1") == 0;
  double t_ctxt = NAN, t_cbin = NAN;
  if (have_colmap) {
    fs::create_directories(dir / "c");
    std::string base = "colmap model_converter --output_path " + (dir / "c").string();
    t_ctxt = BestOf(repeat, [&] {
      (void)!std::system(
          (base + " --input_path " + (dir / "txt").string() + " --output_type TXT >/dev/null 2>&1")
              .c_str());
    });
    t_cbin = BestOf(repeat, [&] {
      (void)!std::system(
          (base + " --input_path " + (dir / "bin").string() + " --output_type BIN >/dev/null 2>&1")
              .c_str());
    });
  }
  fs::remove_all(dir);
  std::printf("orb2colmap benchmark: %zu frames from %zu keyframes, best of %d\n", frames,
              keys.size(), repeat);
  std::printf("%-34s %10s %12s\n", "stage", "ms", "us/frame");
  auto row = [&](const char* name, double s) {
    std::printf("%-34s %10.1f %12.3f\n", name, s * 1e3, s * 1e6 / static_cast<double>(frames));
  };
  row("interpolate + convert (ours)", t_interp);
  row("  baseline: Eigen slerp only", t_eigen);
  row("write images.txt (ours)", t_wtxt);
  row("read images.txt (ours)", t_rtxt);
  row("write images.bin (ours)", t_wbin);
  row("read images.bin (ours)", t_rbin);
  if (have_colmap) {
    row("  baseline: colmap TXT read+write", t_ctxt);
    row("  baseline: colmap BIN read+write", t_cbin);
    std::printf("ratios (baseline / ours): text read+write %.2fx, binary read+write %.2fx\n",
                t_ctxt / (t_wtxt + t_rtxt), t_cbin / (t_wbin + t_rbin));
    const std::string n = std::to_string(frames) + " frames";
    mvtm::bench::Report("orb2colmap", "images.txt read+write, " + n, (t_wtxt + t_rtxt) * 1e3, "ms",
                        "colmap model_converter TXT", t_ctxt * 1e3);
    mvtm::bench::Report("orb2colmap", "images.bin read+write, " + n, (t_wbin + t_rbin) * 1e3, "ms",
                        "colmap model_converter BIN", t_cbin * 1e3);
  }
  return 0;
}
