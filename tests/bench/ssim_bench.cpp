// bench_ssim — mean SSIM of one real image pair: mvtm::Ssim (double, separable, threads over
// rows) against the common OpenCV recipe (float, cv::GaussianBlur 11×11 sigma 1.5, from the
// OpenCV "Video Input with OpenCV and similarity measurement" tutorial).
//
// Pairs: $MVTM_DATA/kitti_odom01_f000-050/image_0/000000.png + 000001.png (1241×376 grey) and
// $MVTM_DATA/camvid_0016E5_seg/images/0016E5_07959.png + 07961 (480×360 colour); a seeded random
// pair of the same size stands in when the data is missing. ssim_vs_skimage.py runs this
// program and times scikit-image on the same pairs to print the ratios of one run.
#include <benchmark/benchmark.h>

#include <cstdlib>
#include <filesystem>
#include <opencv2/core.hpp>
#include <opencv2/imgproc.hpp>
#include <random>
#include <string>

#include "image/image.h"
#include "image/ssim.h"

namespace {

namespace fs = std::filesystem;

std::string DataDir() {
  const char* env = std::getenv("MVTM_DATA");
  return env && *env ? env : MVTM_DATA_DEFAULT;
}

mvtm::Image Random(int w, int h, int c, unsigned seed) {
  mvtm::Image img(w, h, c, 8);
  std::mt19937 rng(seed);
  std::uniform_int_distribution<int> d(0, 255);
  for (float& v : img.data) v = static_cast<float>(d(rng));
  return img;
}

struct Pair {
  mvtm::Image a, b;
  cv::Mat ma, mb;  // 8-bit, as decoded
};

const Pair& LoadPair(bool colour) {
  static Pair grey, rgb;
  Pair& p = colour ? rgb : grey;
  if (p.a.empty()) {
    const fs::path dir = DataDir();
    const fs::path fa = colour ? dir / "camvid_0016E5_seg/images/0016E5_07959.png"
                               : dir / "kitti_odom01_f000-050/image_0/000000.png";
    const fs::path fb = colour ? dir / "camvid_0016E5_seg/images/0016E5_07961.png"
                               : dir / "kitti_odom01_f000-050/image_0/000001.png";
    if (fs::exists(fa) && fs::exists(fb)) {
      p.a = mvtm::ReadImage(fa.string());
      p.b = mvtm::ReadImage(fb.string());
    } else {
      p.a = colour ? Random(480, 360, 3, 1) : Random(1241, 376, 1, 1);
      p.b = colour ? Random(480, 360, 3, 2) : Random(1241, 376, 1, 2);
    }
    const int type = CV_MAKETYPE(CV_8U, p.a.channels);
    cv::Mat(p.a.height, p.a.width, CV_MAKETYPE(CV_32F, p.a.channels), p.a.data.data())
        .convertTo(p.ma, type);
    cv::Mat(p.b.height, p.b.width, CV_MAKETYPE(CV_32F, p.b.channels), p.b.data.data())
        .convertTo(p.mb, type);
  }
  return p;
}

// The OpenCV tutorial's getMSSIM(), verbatim apart from returning the channel mean.
double OpenCvSsim(const cv::Mat& i1, const cv::Mat& i2) {
  const double C1 = 6.5025, C2 = 58.5225;
  int d = CV_32F;
  cv::Mat I1, I2;
  i1.convertTo(I1, d);
  i2.convertTo(I2, d);
  cv::Mat I2_2 = I2.mul(I2);
  cv::Mat I1_2 = I1.mul(I1);
  cv::Mat I1_I2 = I1.mul(I2);
  cv::Mat mu1, mu2;
  cv::GaussianBlur(I1, mu1, cv::Size(11, 11), 1.5);
  cv::GaussianBlur(I2, mu2, cv::Size(11, 11), 1.5);
  cv::Mat mu1_2 = mu1.mul(mu1);
  cv::Mat mu2_2 = mu2.mul(mu2);
  cv::Mat mu1_mu2 = mu1.mul(mu2);
  cv::Mat sigma1_2, sigma2_2, sigma12;
  cv::GaussianBlur(I1_2, sigma1_2, cv::Size(11, 11), 1.5);
  sigma1_2 -= mu1_2;
  cv::GaussianBlur(I2_2, sigma2_2, cv::Size(11, 11), 1.5);
  sigma2_2 -= mu2_2;
  cv::GaussianBlur(I1_I2, sigma12, cv::Size(11, 11), 1.5);
  sigma12 -= mu1_mu2;
  cv::Mat t1, t2, t3;
  t1 = 2 * mu1_mu2 + C1;
  t2 = 2 * sigma12 + C2;
  t3 = t1.mul(t2);
  t1 = mu1_2 + mu2_2 + C1;
  t2 = sigma1_2 + sigma2_2 + C2;
  t1 = t1.mul(t2);
  cv::Mat ssim_map;
  cv::divide(t3, t1, ssim_map);
  cv::Scalar mssim = cv::mean(ssim_map);
  double sum = 0;
  for (int c = 0; c < i1.channels(); ++c) sum += mssim[c];
  return sum / i1.channels();
}

void SetInfo(benchmark::State& state, const Pair& p, double ssim) {
  state.counters["width"] = p.a.width;
  state.counters["height"] = p.a.height;
  state.counters["channels"] = p.a.channels;
  state.counters["ssim"] = ssim;
}

// Arguments: colour (0/1), threads (0 = all cores), instruction set (mvtm::SimdLevel:
// 0 best, 1 baseline, 2 AVX2, 3 AVX-512).
void BM_MvtmSsim(benchmark::State& state) {
  const Pair& p = LoadPair(state.range(0) != 0);
  mvtm::SsimOptions options;
  options.threads = static_cast<int>(state.range(1));
  options.simd = static_cast<mvtm::SimdLevel>(state.range(2));
  double s = 0;
  for (auto _ : state) benchmark::DoNotOptimize(s = mvtm::Ssim(p.a, p.b, options));
  SetInfo(state, p, s);
}
BENCHMARK(BM_MvtmSsim)
    ->ArgNames({"colour", "threads", "simd"})
    ->Args({0, 0, 0})
    ->Args({0, 1, 0})
    ->Args({1, 0, 0})
    ->Args({1, 1, 0})
    ->Args({0, 1, 1})
    ->Args({0, 1, 2})
    ->Args({0, 1, 3})
    ->Unit(benchmark::kMillisecond)
    ->UseRealTime();

// SSIM + NCC + PSNR, as the ssim tool computes them.
void BM_MvtmCompare(benchmark::State& state) {
  const Pair& p = LoadPair(state.range(0) != 0);
  mvtm::SsimOptions options;
  double s = 0;
  for (auto _ : state) benchmark::DoNotOptimize(s = mvtm::Compare(p.a, p.b, options).ssim);
  SetInfo(state, p, s);
}
BENCHMARK(BM_MvtmCompare)
    ->ArgNames({"colour"})
    ->Arg(0)
    ->Arg(1)
    ->Unit(benchmark::kMillisecond)
    ->UseRealTime();

// Arguments: colour (0/1), threads (0 = OpenCV's default, all cores; 1 = one thread).
void BM_OpenCvRecipe(benchmark::State& state) {
  const Pair& p = LoadPair(state.range(0) != 0);
  const int saved = cv::getNumThreads();
  if (state.range(1) > 0) cv::setNumThreads(static_cast<int>(state.range(1)));
  double s = 0;
  for (auto _ : state) benchmark::DoNotOptimize(s = OpenCvSsim(p.ma, p.mb));
  SetInfo(state, p, s);
  state.counters["cv_threads"] = cv::getNumThreads();
  cv::setNumThreads(saved);
}
BENCHMARK(BM_OpenCvRecipe)
    ->ArgNames({"colour", "threads"})
    ->Args({0, 0})
    ->Args({0, 1})
    ->Args({1, 0})
    ->Args({1, 1})
    ->Unit(benchmark::kMillisecond)
    ->UseRealTime();

}  // namespace

BENCHMARK_MAIN();
