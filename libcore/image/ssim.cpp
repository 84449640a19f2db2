#include "image/ssim.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <limits>
#include <sstream>
#include <thread>

namespace mvtm {

// The row kernels are compiled for AVX-512, AVX2 and baseline x86-64 and picked at run time
// (no -march=native in the build). FP contraction stays off so every clone rounds the SSIM
// formula alike and identical images give exactly 1.
#if defined(__GNUC__) && !defined(__clang__) && defined(__x86_64__) && defined(__linux__)
#define MVTM_SIMD_CLONES \
  __attribute__((target_clones("arch=x86-64-v4", "arch=x86-64-v3", "default")))
#define MVTM_INLINE inline __attribute__((always_inline))
#else
#define MVTM_SIMD_CLONES
#define MVTM_INLINE inline
#endif

namespace {

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();
constexpr int kLanes = 4;  // partial sums per row: vectorisable, and the same order everywhere

std::string Dims(const Image& img) {
  std::ostringstream s;
  s << img.width << "x" << img.height << "x" << img.channels;
  return s.str();
}

// scipy.ndimage mode 'reflect' (d c b a | a b c d | d c b a); valid for -n <= i < 2n.
inline int Reflect(int i, int n) { return i < 0 ? -i - 1 : (i >= n ? 2 * n - i - 1 : i); }

// One colour channel of a pair, as contiguous float planes.
struct PlanePair {
  const float* x;
  const float* y;
};

struct Job {
  int w = 0, h = 0, r = 0;
  const double* wt = nullptr;  // 2r+1 weights
  double c1 = 0, c2 = 0;
  const uint8_t* mask = nullptr;  // w*h, 1 = inside; null = all inside
  float* map = nullptr;           // w*h; channel maps are summed here
};

struct Scratch {
  std::array<std::vector<double>, 5> v;  // vertical pass of x, y, x², y², xy; r pad each side
  std::vector<double> s;                 // one row of the SSIM map
  std::vector<const float*> xr, yr;      // the 2r+1 source rows of the window

  Scratch(int w, int r) : s(w), xr(2 * r + 1), yr(2 * r + 1) {
    for (auto& b : v) b.assign(w + 2 * r, 0.0);
  }
};

// kN adjacent columns of the vertical pass (scipy filters axis 0 first): the window sums of
// x, y, x², y², xy. Fixed-size blocks keep the accumulators in vector registers.
template <int kR, int kN>
MVTM_INLINE void VerticalBlock(const float* const* xr, const float* const* yr,
                               const double* __restrict wt, int taps, int j,
                               double* const* __restrict v) {
  if (kR >= 0) taps = 2 * kR + 1;
  double acc[5][kN] = {};
  for (int k = 0; k < taps; ++k) {
    const double wk = wt[k];
    const float* __restrict x = xr[k] + j;
    const float* __restrict y = yr[k] + j;
    for (int l = 0; l < kN; ++l) {
      const double a = x[l], b = y[l];
      acc[0][l] += wk * a;
      acc[1][l] += wk * b;
      acc[2][l] += wk * (a * a);
      acc[3][l] += wk * (b * b);
      acc[4][l] += wk * (a * b);
    }
  }
  for (int q = 0; q < 5; ++q)
    for (int l = 0; l < kN; ++l) v[q][j + l] = acc[q][l];
}

// kN adjacent columns of the horizontal pass fused with the SSIM formula (skimage's operation
// order). h[q][j + k] is the vertical sum at column j - r + k.
template <int kR, int kN>
MVTM_INLINE void HorizontalBlock(const double* const* h, const double* __restrict wt, int taps,
                                 double c1, double c2, int j, double* __restrict s) {
  if (kR >= 0) taps = 2 * kR + 1;
  double u[5][kN] = {};
  for (int k = 0; k < taps; ++k) {
    const double wk = wt[k];
    for (int q = 0; q < 5; ++q) {
      const double* __restrict hq = h[q] + j + k;
      for (int l = 0; l < kN; ++l) u[q][l] += wk * hq[l];
    }
  }
  for (int l = 0; l < kN; ++l) {
    const double ux = u[0][l], uy = u[1][l];
    const double var_x = u[2][l] - ux * ux;
    const double var_y = u[3][l] - uy * uy;
    const double cov = u[4][l] - ux * uy;
    const double a1 = 2 * ux * uy + c1;
    const double a2 = 2 * cov + c2;
    const double b1 = ux * ux + uy * uy + c1;
    const double b2 = var_x + var_y + c2;
    s[j + l] = (a1 * a2) / (b1 * b2);
  }
}

constexpr int kBlock = 8;  // columns per block: one AVX-512 register of doubles

// SSIM map of row i into sc.s[col_begin, col_end). kR >= 0 fixes the radius at compile time
// (the tap loops unroll); kR < 0 takes job.r.
template <int kR>
MVTM_INLINE void SsimRow(const Job& job, PlanePair p, int i, int col_begin, int col_end,
                         Scratch& sc) {
  const int r = kR >= 0 ? kR : job.r;
  const int taps = 2 * r + 1;
  const int w = job.w;
  for (int k = 0; k < taps; ++k) {
    const size_t row = static_cast<size_t>(Reflect(i - r + k, job.h));
    sc.xr[k] = p.x + row * w;
    sc.yr[k] = p.y + row * w;
  }
  double* v[5];
  for (int q = 0; q < 5; ++q) v[q] = sc.v[q].data() + r;
  int j = 0;
  for (; j + kBlock <= w; j += kBlock)
    VerticalBlock<kR, kBlock>(sc.xr.data(), sc.yr.data(), job.wt, taps, j, v);
  for (; j < w; ++j) VerticalBlock<kR, 1>(sc.xr.data(), sc.yr.data(), job.wt, taps, j, v);
  if (col_begin < r || col_end > w - r) {  // the map needs the mirrored columns too
    for (int q = 0; q < 5; ++q) {
      for (int t = 1; t <= r; ++t) {
        v[q][-t] = v[q][t - 1];
        v[q][w - 1 + t] = v[q][w - t];
      }
    }
  }
  const double* h[5];
  for (int q = 0; q < 5; ++q) h[q] = v[q] - r;
  double* s = sc.s.data();
  j = col_begin;
  for (; j + kBlock <= col_end; j += kBlock)
    HorizontalBlock<kR, kBlock>(h, job.wt, taps, job.c1, job.c2, j, s);
  for (; j < col_end; ++j) HorizontalBlock<kR, 1>(h, job.wt, taps, job.c1, job.c2, j, s);
}

// Sum of s[begin, end) over mask pixels (all when mask is null), kLanes partial sums.
MVTM_INLINE double MaskedRowSum(const double* __restrict s, const uint8_t* __restrict m, int begin,
                           int end) {
  double lane[kLanes] = {};
  int j = begin;
  if (m) {
    for (; j + kLanes <= end; j += kLanes)
      for (int l = 0; l < kLanes; ++l) lane[l] += m[j + l] ? s[j + l] : 0.0;
  } else {
    for (; j + kLanes <= end; j += kLanes)
      for (int l = 0; l < kLanes; ++l) lane[l] += s[j + l];
  }
  double tail = 0;
  for (; j < end; ++j) tail += (!m || m[j]) ? s[j] : 0.0;
  return ((lane[0] + lane[1]) + (lane[2] + lane[3])) + tail;
}

// Rows [row_begin, row_end) of one channel: per-row sums of the SSIM map over the cropped
// columns (row_sum[i], rows inside the cropped band only) and, with a map, the whole row.
template <int kR>
MVTM_INLINE void SsimRowsImpl(const Job& job, PlanePair p, int row_begin, int row_end, bool first,
                         Scratch& sc, double* row_sum) {
  const int r = kR >= 0 ? kR : job.r;
  const int w = job.w;
  const int col_begin = job.map ? 0 : r;
  const int col_end = job.map ? w : w - r;
  for (int i = row_begin; i < row_end; ++i) {
    SsimRow<kR>(job, p, i, col_begin, col_end, sc);
    if (i >= r && i < job.h - r) {
      const uint8_t* m = job.mask ? job.mask + static_cast<size_t>(i) * w : nullptr;
      row_sum[i] = MaskedRowSum(sc.s.data(), m, r, w - r);
    }
    if (job.map) {
      float* out = job.map + static_cast<size_t>(i) * w;
      const double* s = sc.s.data();
      if (first) {
        for (int j = 0; j < w; ++j) out[j] = static_cast<float>(s[j]);
      } else {
        for (int j = 0; j < w; ++j) out[j] += static_cast<float>(s[j]);
      }
    }
  }
}

MVTM_SIMD_CLONES void SsimRowsR5(const Job& job, PlanePair p, int row_begin, int row_end,
                                 bool first, Scratch& sc, double* row_sum) {
  SsimRowsImpl<5>(job, p, row_begin, row_end, first, sc, row_sum);
}

MVTM_SIMD_CLONES void SsimRowsAny(const Job& job, PlanePair p, int row_begin, int row_end,
                                  bool first, Scratch& sc, double* row_sum) {
  SsimRowsImpl<-1>(job, p, row_begin, row_end, first, sc, row_sum);
}

// Per-row sums for NCC and PSNR of one channel, samples shifted by (x0, y0) so that flat
// images give exactly zero variance and integer samples sum exactly.
enum Moment { kSx, kSy, kSxx, kSyy, kSxy, kSdd, kMoments };
using RowMoments = std::array<double, kMoments>;

MVTM_SIMD_CLONES void MomentRows(const Job& job, PlanePair p, double x0, double y0,
                                 int row_begin, int row_end, RowMoments* out) {
  const int w = job.w;
  for (int i = row_begin; i < row_end; ++i) {
    const size_t o = static_cast<size_t>(i) * w;
    const float* __restrict x = p.x + o;
    const float* __restrict y = p.y + o;
    const uint8_t* __restrict m = job.mask ? job.mask + o : nullptr;
    double lane[kMoments][kLanes] = {};
    int j = 0;
    for (; j + kLanes <= w; j += kLanes) {
      for (int l = 0; l < kLanes; ++l) {
        const double f = (!m || m[j + l]) ? 1.0 : 0.0;
        const double a = (x[j + l] - x0) * f, b = (y[j + l] - y0) * f;
        const double d = (static_cast<double>(x[j + l]) - y[j + l]) * f;
        lane[kSx][l] += a;
        lane[kSy][l] += b;
        lane[kSxx][l] += a * a;
        lane[kSyy][l] += b * b;
        lane[kSxy][l] += a * b;
        lane[kSdd][l] += d * d;
      }
    }
    RowMoments sum{};
    for (; j < w; ++j) {
      const double f = (!m || m[j]) ? 1.0 : 0.0;
      const double a = (x[j] - x0) * f, b = (y[j] - y0) * f;
      const double d = (static_cast<double>(x[j]) - y[j]) * f;
      sum[kSx] += a;
      sum[kSy] += b;
      sum[kSxx] += a * a;
      sum[kSyy] += b * b;
      sum[kSxy] += a * b;
      sum[kSdd] += d * d;
    }
    for (int q = 0; q < kMoments; ++q)
      out[i][q] = ((lane[q][0] + lane[q][1]) + (lane[q][2] + lane[q][3])) + sum[q];
  }
}

int ThreadCount(int requested, int rows) {
  int t = requested > 0 ? requested : static_cast<int>(std::thread::hardware_concurrency());
  return std::clamp(t, 1, std::max(1, rows / 16));  // a thread gets at least 16 rows
}

// Runs fn(k, t) for k = 0..t-1, k = 0 on the calling thread.
template <typename Fn>
void RunThreads(int t, Fn fn) {
  std::vector<std::thread> pool;
  pool.reserve(t - 1);
  for (int k = 1; k < t; ++k) pool.emplace_back(fn, k, t);
  fn(0, t);
  for (auto& th : pool) th.join();
}

Similarity CompareImpl(const Image& a, const Image& b, const SsimOptions& options,
                       const Image* mask, Image* map, bool with_moments) {
  options.Check();
  if (a.width != b.width || a.height != b.height || a.channels != b.channels)
    throw SizeMismatchError("images differ in size: " + Dims(a) + " vs " + Dims(b));
  if (a.empty()) throw Error("image has no pixels");
  if (a.bits != b.bits)
    throw Error("images differ in bit depth: " + std::to_string(a.bits) + " vs " +
                std::to_string(b.bits) + " bits (samples are compared in file scale)");
  if (mask && (mask->width != a.width || mask->height != a.height))
    throw SizeMismatchError("mask is " + std::to_string(mask->width) + "x" +
                            std::to_string(mask->height) + ", images are " +
                            std::to_string(a.width) + "x" + std::to_string(a.height));
  const int w = a.width, h = a.height, r = options.Radius();
  const int win = 2 * r + 1;
  if (w < win || h < win) {
    std::ostringstream s;
    s << "image is " << w << "x" << h << ", smaller than the " << win << "x" << win
      << " SSIM window (sigma " << options.sigma << ", truncate " << options.truncate << ")";
    throw Error(s.str());
  }

  Similarity result;
  result.data_range = options.DataRangeFor(a.bits);
  const std::vector<double> wt = GaussianWeights(options.sigma, r);
  const int nc = (a.channels == 2 || a.channels == 4) ? a.channels - 1 : a.channels;
  const size_t npix = a.pixels();

  // Contiguous float planes per colour channel (no copy for single-channel images).
  std::vector<std::vector<float>> planes;
  std::vector<PlanePair> pairs(nc);
  if (a.channels == 1) {
    pairs[0] = {a.data.data(), b.data.data()};
  } else {
    planes.assign(2 * nc, std::vector<float>(npix));
    for (int c = 0; c < nc; ++c) {
      float* px = planes[2 * c].data();
      float* py = planes[2 * c + 1].data();
      for (size_t q = 0; q < npix; ++q) {
        px[q] = a.data[q * a.channels + c];
        py[q] = b.data[q * b.channels + c];
      }
      pairs[c] = {px, py};
    }
  }

  std::vector<uint8_t> inside;
  if (mask) {
    inside.assign(npix, 0);
    for (size_t q = 0; q < npix; ++q)
      for (int c = 0; c < mask->channels; ++c)
        if (mask->data[q * mask->channels + c] != 0.f) inside[q] = 1;
  }

  Job job;
  job.w = w;
  job.h = h;
  job.r = r;
  job.wt = wt.data();
  job.c1 = std::pow(options.k1 * result.data_range, 2);
  job.c2 = std::pow(options.k2 * result.data_range, 2);
  job.mask = mask ? inside.data() : nullptr;
  if (map) {
    *map = Image(w, h, 1, 32);
    job.map = map->data.data();
  }

  // Rows whose SSIM is needed: the cropped band, or every row for the map.
  const int ssim_begin = map ? 0 : r, ssim_end = map ? h : h - r;
  std::vector<std::vector<double>> row_sum(nc, std::vector<double>(h, 0.0));
  std::vector<std::vector<RowMoments>> moments(with_moments ? nc : 0,
                                               std::vector<RowMoments>(h, RowMoments{}));
  std::vector<double> x0(nc), y0(nc);
  for (int c = 0; c < nc; ++c) {
    x0[c] = pairs[c].x[0];
    y0[c] = pairs[c].y[0];
  }
  const int t = ThreadCount(options.threads, ssim_end - ssim_begin);
  std::vector<Scratch> scratch;
  scratch.reserve(t);
  for (int k = 0; k < t; ++k) scratch.emplace_back(w, r);

  RunThreads(t, [&](int k, int n) {
    const int i0 = ssim_begin + (ssim_end - ssim_begin) * k / n;
    const int i1 = ssim_begin + (ssim_end - ssim_begin) * (k + 1) / n;
    for (int c = 0; c < nc; ++c) {
      if (r == 5) {
        SsimRowsR5(job, pairs[c], i0, i1, c == 0, scratch[k], row_sum[c].data());
      } else {
        SsimRowsAny(job, pairs[c], i0, i1, c == 0, scratch[k], row_sum[c].data());
      }
    }
    if (with_moments) {
      for (int c = 0; c < nc; ++c)
        MomentRows(job, pairs[c], x0[c], y0[c], h * k / n, h * (k + 1) / n, moments[c].data());
    }
  });

  if (map && nc > 1) {
    for (float& v : map->data) v /= static_cast<float>(nc);
  }

  // Pixel counts: SSIM over cropped band ∩ mask, NCC/PSNR over the mask.
  if (mask) {
    for (size_t q = 0; q < npix; ++q) result.pixels += inside[q];
    for (int i = r; i < h - r; ++i)
      for (int j = r; j < w - r; ++j) result.ssim_pixels += inside[static_cast<size_t>(i) * w + j];
  } else {
    result.pixels = npix;
    result.ssim_pixels = static_cast<size_t>(w - 2 * r) * (h - 2 * r);
  }

  double ssim_total = 0;
  for (int c = 0; c < nc; ++c) {
    double sum = 0;
    for (int i = r; i < h - r; ++i) sum += row_sum[c][i];
    ssim_total += sum / static_cast<double>(result.ssim_pixels);
  }
  result.ssim = result.ssim_pixels ? ssim_total / nc : kNaN;

  if (with_moments) {
    const double n = static_cast<double>(result.pixels);
    double ncc_total = 0, sdd = 0;
    for (int c = 0; c < nc; ++c) {
      RowMoments m{};
      for (int i = 0; i < h; ++i)
        for (int q = 0; q < kMoments; ++q) m[q] += moments[c][i][q];
      const double var_x = m[kSxx] - m[kSx] * m[kSx] / n;
      const double var_y = m[kSyy] - m[kSy] * m[kSy] / n;
      const double cov = m[kSxy] - m[kSx] * m[kSy] / n;
      ncc_total += (var_x > 0 && var_y > 0) ? cov / std::sqrt(var_x * var_y) : kNaN;
      sdd += m[kSdd];
    }
    result.ncc = result.pixels ? ncc_total / nc : kNaN;
    const double mse = sdd / (n * nc);
    result.psnr = !result.pixels ? kNaN
                  : mse == 0     ? std::numeric_limits<double>::infinity()
                                 : 10 * std::log10(result.data_range * result.data_range / mse);
  } else {
    result.ncc = result.psnr = kNaN;
  }
  return result;
}

}  // namespace

void SsimOptions::Check() const {
  auto bad = [](const std::string& what) { throw UsageError(what); };
  std::ostringstream s;
  if (!(sigma > 0) || !std::isfinite(sigma)) {
    s << "sigma must be > 0, got " << sigma;
    bad(s.str());
  }
  if (!(k1 >= 0) || !std::isfinite(k1)) {
    s << "k1 must be >= 0, got " << k1;
    bad(s.str());
  }
  if (!(k2 >= 0) || !std::isfinite(k2)) {
    s << "k2 must be >= 0, got " << k2;
    bad(s.str());
  }
  if (!(data_range >= 0) || !std::isfinite(data_range)) {
    s << "data range must be > 0 (or 0 for the bit depth), got " << data_range;
    bad(s.str());
  }
  if (!(truncate > 0) || !std::isfinite(truncate)) {
    s << "truncate must be > 0, got " << truncate;
    bad(s.str());
  }
  if (truncate * sigma > 1000) {
    s << "window radius truncate*sigma must be <= 1000, got " << truncate * sigma;
    bad(s.str());
  }
  if (threads < 0) {
    s << "threads must be >= 0, got " << threads;
    bad(s.str());
  }
}

int SsimOptions::Radius() const { return static_cast<int>(truncate * sigma + 0.5); }

double SsimOptions::DataRangeFor(int bits) const {
  if (data_range > 0) return data_range;
  return bits == 8 ? 255.0 : bits == 16 ? 65535.0 : 1.0;
}

std::vector<double> GaussianWeights(double sigma, int radius) {
  std::vector<double> wt(2 * radius + 1);
  const double s2 = sigma * sigma;
  double sum = 0;
  for (int k = -radius; k <= radius; ++k) {
    wt[k + radius] = std::exp(-0.5 / s2 * (static_cast<double>(k) * k));
    sum += wt[k + radius];
  }
  for (double& v : wt) v /= sum;
  return wt;
}

Similarity Compare(const Image& a, const Image& b, const SsimOptions& options, const Image* mask,
                   Image* map) {
  return CompareImpl(a, b, options, mask, map, true);
}

double Ssim(const Image& a, const Image& b, const SsimOptions& options, const Image* mask,
            Image* map) {
  return CompareImpl(a, b, options, mask, map, false).ssim;
}

}  // namespace mvtm
