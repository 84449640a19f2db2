// segtrack's tracking at 1241x376 (KITTI size), single thread, PNG decoding excluded.
//
// The frames are the real CamVid labels (MVTM_DATA/camvid_0016E5_seg, 480x360) scaled to
// 1241x376 by nearest neighbour, or, without the data, 60 synthetic frames of moving boxes.
// Timed (best of --repeat runs), from decoded label images (float samples, as ReadImage gives
// them) to finished output masks in memory:
//   segtrack    class-id decoding + blobs + association, then smoothing, gap filling, rejection,
//               and rendering every frame's mask
//   baseline    a bare cv::connectedComponentsWithStats pass over the same frames' binary masks
// The ratio segtrack/baseline in frames/s survives a noisy shared host; the target is >= 500 fps.
// usage: bench_segtrack [--repeat R] [--short]
#include <algorithm>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <functional>
#include <opencv2/core.hpp>
#include <opencv2/imgproc.hpp>
#include <string>
#include <vector>

#include "bench_util.h"
#include "image/image.h"
#include "track/labels.h"
#include "track/tracker.h"

using namespace mvtm;
namespace fs = std::filesystem;

using bench::BestOf;

int main(int argc, char** argv) {
  int repeat = 5;
  for (int i = 1; i < argc; ++i) {
    std::string a = argv[i];
    if (a == "--repeat" && i + 1 < argc)
      repeat = std::max(1, std::atoi(argv[++i]));
    else if (a == "--short")
      repeat = 1;
  }
  cv::setNumThreads(1);
  const int W = 1241, H = 376;
  std::vector<Image> frames;
  const char* env = std::getenv("MVTM_DATA");
  const fs::path dir =
      fs::path(env && *env ? env : MVTM_DATA_DEFAULT) / "camvid_0016E5_seg" / "labels";
  std::string source;
  if (fs::is_directory(dir)) {
    std::vector<fs::path> files;
    for (const auto& e : fs::directory_iterator(dir))
      if (e.path().extension() == ".png") files.push_back(e.path());
    std::sort(files.begin(), files.end());
    for (const auto& f : files) {
      const Image src = ReadImage(f.string());
      Image im(W, H, 1, 8);
      for (int y = 0; y < H; ++y)
        for (int x = 0; x < W; ++x) im.at(x, y) = src.at(x * src.width / W, y * src.height / H);
      frames.push_back(std::move(im));
    }
    source = "CamVid 0016E5 labels scaled to 1241x376";
  } else {
    for (int f = 0; f < 60; ++f) {
      Image im(W, H, 1, 8, 3.f);
      for (int v = 0; v < 4; ++v) {
        const int x0 = 100 + 250 * v + 6 * f * (v % 2 ? 1 : -1), y0 = 180 + 20 * v,
                  w = 120 + 10 * v, h = 70;
        for (int y = std::max(0, y0); y < std::min(H, y0 + h); ++y)
          for (int x = std::max(0, x0); x < std::min(W, x0 + w); ++x) im.at(x, y) = 8.f;
      }
      frames.push_back(std::move(im));
    }
    source = "60 synthetic frames (no MVTM_DATA)";
  }
  const size_t n = frames.size();
  const LabelDecoder decoder = LabelDecoder::ClassIds({8});

  std::vector<std::vector<uint8_t>> binary(n);
  for (size_t i = 0; i < n; ++i) decoder.Decode(frames[i], "", binary[i]);

  size_t kept_pixels = 0;
  TrackSummary summary;
  const double t_ours = BestOf(repeat, [&] {
    Tracker tracker(W, H, TrackOptions{});
    std::vector<uint8_t> vehicle;
    for (const Image& im : frames) {
      decoder.Decode(im, "", vehicle);
      tracker.AddFrame(vehicle.data());
    }
    const TrackResult res = tracker.Finish();
    std::vector<uint8_t> mask;
    kept_pixels = 0;
    for (size_t i = 0; i < n; ++i) {
      res.RenderMask(static_cast<int>(i), 0, mask);
      kept_pixels += static_cast<size_t>(std::count(mask.begin(), mask.end(), 255));
    }
    summary = res.summary;
  });
  size_t components = 0;
  const double t_base = BestOf(repeat, [&] {
    cv::Mat labels, stats, centroids;
    components = 0;
    for (size_t i = 0; i < n; ++i) {
      const cv::Mat in(H, W, CV_8U, binary[i].data());
      components += static_cast<size_t>(
          cv::connectedComponentsWithStats(in, labels, stats, centroids, 8, CV_32S) - 1);
    }
  });
  const double fps = n / t_ours, base_fps = n / t_base;
  std::printf("segtrack benchmark: %zu frames, %s, 1 thread, best of %d\n", n, source.c_str(),
              repeat);
  std::printf("  %zu tracks (%d kept), %zu blobs, %zu mask pixels\n",
              static_cast<size_t>(summary.tracks), summary.kept, components, kept_pixels);
  std::printf("%-44s %10s %10s\n", "stage", "ms/frame", "frames/s");
  std::printf("%-44s %10.3f %10.0f\n", "segtrack (decode+blobs+track+fill+masks)", 1e3 * t_ours / n,
              fps);
  std::printf("%-44s %10.3f %10.0f\n", "baseline cv::connectedComponentsWithStats",
              1e3 * t_base / n, base_fps);
  std::printf("ratio segtrack/baseline frames/s: %.2f; target >= 500 fps: %s\n", fps / base_fps,
              fps >= 500 ? "met" : "NOT met");
  return 0;
}
