// segtrack at 1241x376 (KITTI size): the tracking core and the whole job, each against an
// OpenCV baseline timed in the same run (ratios survive a noisy shared host).
//
// The frames are the real CamVid labels (MVTM_DATA/camvid_0016E5_seg, 480x360) scaled to
// 1241x376 by nearest neighbour, played forwards then backwards (120 frames), or, without the
// data, 120 synthetic frames of moving boxes. Timed (best of --repeat runs):
//   core        single thread, from decoded label images (float samples, as ReadImage gives
//               them) to finished output masks in memory: class-id decoding + blobs +
//               association, then smoothing, gap filling, rejection, rendering every mask
//   cv CC       a bare cv::connectedComponentsWithStats pass over the same frames' vehicle masks
//   job         RunSegtrack (what `segtrack -q LABELS WS` does) on the frames as 8-bit label
//               PNGs in a temporary folder: read, track, write masks/, tracks.tsv, provenance
//   cv job      the OpenCV recipe, frame after frame: cv::imread, vehicle class -> mask,
//               cv::connectedComponentsWithStats, cv::imwrite of the mask (default settings)
// Both jobs run with OpenCV's default thread count (segtrack reads and writes on all cores).
// The targets: core >= 500 frames/s; job/cv job >= 1.
// usage: bench_segtrack [--repeat R] [--short]
#include <time.h>
#include <unistd.h>

#include <algorithm>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <opencv2/core.hpp>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>
#include <string>
#include <vector>

#include "bench_util.h"
#include "image/image.h"
#include "segtrack.h"
#include "track/labels.h"
#include "track/tracker.h"

using namespace mvtm;
namespace fs = std::filesystem;

using bench::BestOf;

namespace {

constexpr int W = 1241, H = 376, kFrames = 120, kCar = 8;

// The label frames (8-bit class ids) and where they came from.
std::vector<cv::Mat> LoadFrames(std::string& source) {
  std::vector<cv::Mat> frames;
  const char* env = std::getenv("MVTM_DATA");
  const fs::path dir =
      fs::path(env && *env ? env : MVTM_DATA_DEFAULT) / "camvid_0016E5_seg" / "labels";
  if (fs::is_directory(dir)) {
    std::vector<fs::path> files;
    for (const auto& e : fs::directory_iterator(dir))
      if (e.path().extension() == ".png") files.push_back(e.path());
    std::sort(files.begin(), files.end());
    for (const auto& f : files) {
      const Image src = ReadImage(f.string());
      cv::Mat im(H, W, CV_8U);
      for (int y = 0; y < H; ++y)
        for (int x = 0; x < W; ++x)
          im.at<uint8_t>(y, x) =
              static_cast<uint8_t>(src.at(x * src.width / W, y * src.height / H));
      frames.push_back(im);
    }
    for (size_t i = frames.size(); i-- > 0 && frames.size() < kFrames;)
      frames.push_back(frames[i]);  // then backwards
    source = "CamVid 0016E5 labels scaled to 1241x376, forwards and back";
  } else {
    for (int f = 0; f < kFrames; ++f) {
      cv::Mat im(H, W, CV_8U, cv::Scalar(3));
      for (int v = 0; v < 4; ++v) {
        const int x0 = 100 + 250 * v + 3 * f * (v % 2 ? 1 : -1), y0 = 180 + 20 * v,
                  w = 120 + 10 * v, h = 70;
        cv::rectangle(im, cv::Rect(x0, y0, w, h), cv::Scalar(kCar), cv::FILLED);
      }
      frames.push_back(im);
    }
    source = "120 synthetic frames (no MVTM_DATA)";
  }
  return frames;
}

// CPU time of the whole process (all threads), seconds.
double CpuSeconds() {
  timespec t;
  clock_gettime(CLOCK_PROCESS_CPUTIME_ID, &t);
  return static_cast<double>(t.tv_sec) + 1e-9 * static_cast<double>(t.tv_nsec);
}

// Keeps the least CPU time of a scope in `best`.
struct CpuAtEnd {
  double start;
  double& best;
  ~CpuAtEnd() { best = std::min(best, CpuSeconds() - start); }
};

Image ToImage(const cv::Mat& m) {
  Image im(m.cols, m.rows, 1, 8);
  std::copy(m.datastart, m.dataend, im.data.begin());
  return im;
}

}  // namespace

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
  std::string source;
  const std::vector<cv::Mat> label_mats = LoadFrames(source);
  const size_t n = label_mats.size();
  std::vector<Image> frames;
  for (const cv::Mat& m : label_mats) frames.push_back(ToImage(m));
  const LabelDecoder decoder = LabelDecoder::ClassIds({kCar});
  std::vector<std::vector<uint8_t>> binary(n);
  for (size_t i = 0; i < n; ++i) decoder.Decode(frames[i], "", binary[i]);

  // The tracking core.
  size_t kept_pixels = 0;
  TrackSummary summary;
  const double t_core = BestOf(repeat, [&] {
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
  const double t_cc = BestOf(repeat, [&] {
    cv::Mat labels, stats, centroids;
    components = 0;
    for (size_t i = 0; i < n; ++i) {
      const cv::Mat in(H, W, CV_8U, binary[i].data());
      components += static_cast<size_t>(
          cv::connectedComponentsWithStats(in, labels, stats, centroids, 8, CV_32S) - 1);
    }
  });

  // The whole job, on label PNGs in a temporary folder.
  const fs::path tmp =
      fs::temp_directory_path() / ("mvtm-bench-segtrack-" + std::to_string(getpid()));
  const fs::path labels = tmp / "labels";
  fs::create_directories(labels);
  std::vector<std::string> names;
  for (size_t i = 0; i < n; ++i) {
    char name[32];
    std::snprintf(name, sizeof name, "%06zu.png", i);
    names.push_back(name);
    cv::imwrite((labels / name).string(), label_mats[i]);
  }
  cv::setNumThreads(-1);  // the jobs as run: OpenCV's default thread count
  // Each run writes into a new folder (a fresh workspace for segtrack), made before the clock
  // starts; the CPU time (all threads) of the least of the runs is kept as well.
  int run = 0;
  auto fresh = [&](const char* what) {
    const fs::path dir = tmp / (what + std::to_string(run++));
    fs::create_directories(dir);
    return dir;
  };
  double cpu_job = 1e300, cpu_cv_job = 1e300;
  const double t_job = BestOf(repeat, [&] {
    SegtrackOptions o;
    o.paths = {labels.string(), fresh("ws").string()};
    o.quiet = true;
    CpuAtEnd at_end{CpuSeconds(), cpu_job};
    RunSegtrack(o);
  });
  const double t_cv_job = BestOf(repeat, [&] {
    const fs::path masks = fresh("cv_masks");
    CpuAtEnd at_end{CpuSeconds(), cpu_cv_job};
    cv::Mat cc, stats, centroids;
    for (const std::string& name : names) {
      const cv::Mat label = cv::imread((labels / name).string(), cv::IMREAD_UNCHANGED);
      const cv::Mat mask = label == kCar;
      cv::connectedComponentsWithStats(mask, cc, stats, centroids, 8, CV_32S);
      cv::imwrite((masks / name).string(), mask);
    }
  });
  fs::remove_all(tmp);

  const double core_fps = n / t_core, cc_fps = n / t_cc, job_fps = n / t_job,
               cv_job_fps = n / t_cv_job;
  std::printf("segtrack benchmark: %zu frames, %s, best of %d; jobs on %d threads\n", n,
              source.c_str(), repeat, cv::getNumThreads());
  std::printf("  %zu tracks (%d kept), %zu blobs, %zu mask pixels\n",
              static_cast<size_t>(summary.tracks), summary.kept, components, kept_pixels);
  std::printf("%-58s %10s %10s %12s\n", "stage", "ms/frame", "frames/s", "CPU ms/frame");
  auto row = [&](const char* what, double t, double cpu) {
    std::printf("%-58s %10.3f %10.0f", what, 1e3 * t / n, n / t);
    if (cpu > 0) std::printf(" %12.3f", 1e3 * cpu / n);
    std::printf("\n");
  };
  row("core: decode+blobs+track+fill+masks in memory, 1 thread", t_core, 0);
  row("cv CC: cv::connectedComponentsWithStats, 1 thread", t_cc, 0);
  row("job: segtrack read+track+write masks/tracks.tsv", t_job, cpu_job);
  row("cv job: imread+connectedComponentsWithStats+imwrite", t_cv_job, cpu_cv_job);
  std::printf("ratio core/cv CC frames/s: %.2f; core target >= 500 fps: %s\n", core_fps / cc_fps,
              core_fps >= 500 ? "met" : "NOT met");
  std::printf("ratio job/cv job frames/s: %.2f; target >= 1: %s\n", job_fps / cv_job_fps,
              job_fps >= cv_job_fps ? "met" : "NOT met");
  const std::string at = " at " + source;
  mvtm::bench::Report("segtrack", "tracking core, 1 thread" + at, core_fps, "fps",
                      "cv::connectedComponentsWithStats, 1 thread", cc_fps);
  mvtm::bench::Report("segtrack", "whole job: read labels, track, write masks" + at, job_fps, "fps",
                      "OpenCV imread + connectedComponentsWithStats + imwrite", cv_job_fps);
  return 0;
}
