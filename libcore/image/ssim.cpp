#include "image/ssim.h"

#include <algorithm>
#include <array>
#include <atomic>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <limits>
#include <sstream>
#include <thread>

// The row kernels are compiled three times, for AVX-512, AVX2+FMA and baseline x86-64, with
// block sizes that fit each register file, and picked at run time (no -march=native in the
// build). Elsewhere only the baseline variant exists.
#if defined(__GNUC__) && !defined(__clang__) && defined(__x86_64__)
#define MVTM_X86_DISPATCH 1
#define MVTM_TARGET(arch) __attribute__((target(arch)))
#define MVTM_INLINE inline __attribute__((always_inline))
#else
#define MVTM_X86_DISPATCH 0
#define MVTM_TARGET(arch)
#define MVTM_INLINE inline
#endif

namespace mvtm {

namespace {

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();
constexpr int kLanes = 4;     // partial sums per row: vectorisable, and the same order everywhere
constexpr int kMaxRows = 4;   // most output rows computed together (see VerticalRows)
constexpr int kMaxBlock = 8;  // most doubles per vector block

std::string Dims(const Image& img) {
  std::ostringstream s;
  s << img.width << "x" << img.height << "x" << img.channels;
  return s.str();
}

// scipy.ndimage mode 'reflect' (d c b a | a b c d | d c b a); valid for -n <= i < 2n.
inline int Reflect(int i, int n) { return i < 0 ? -i - 1 : (i >= n ? 2 * n - i - 1 : i); }

// GCC vector extensions: kB doubles, lowered to whatever the enclosing target offers.
template <int kB>
struct VecOf;
template <>
struct VecOf<2> {
  typedef double type __attribute__((vector_size(16)));
};
template <>
struct VecOf<4> {
  typedef double type __attribute__((vector_size(32)));
};
template <>
struct VecOf<8> {
  typedef double type __attribute__((vector_size(64)));
};

template <int kB>
struct FloatVecOf {
  typedef float type __attribute__((vector_size(kB * sizeof(float))));
};

template <typename V>
MVTM_INLINE V Load(const double* p) {
  V v;
  std::memcpy(&v, p, sizeof v);
  return v;
}
template <typename V>
MVTM_INLINE void Store(double* p, V v) {
  std::memcpy(p, &v, sizeof v);
}
// kB floats converted (exactly) to kB doubles.
template <typename V, int kB>
MVTM_INLINE V LoadFloats(const float* p) {
  typename FloatVecOf<kB>::type f;
  std::memcpy(&f, p, sizeof f);
  return __builtin_convertvector(f, V);
}

// One channel of a pair of interleaved images: sample j of row q is x[(q*w + j) * stride].
struct PlanePair {
  const float* x;
  const float* y;
  int stride;  // channels per pixel
};

struct Job {
  int w = 0, h = 0, r = 0;
  const double* wt = nullptr;  // 2r+1 weights
  double c1 = 0, c2 = 0;
  const uint8_t* mask = nullptr;  // w*h, 1 = inside; null = all inside
  float* map = nullptr;           // w*h; channel maps are summed here
};

// The four planes filtered per channel: x, y, xy and d² = (x − y)². With
//   σx² + σy² = 2σxy + (E[d²] − (µx − µy)²)   and   µx² + µy² = 2µxµy + (µx − µy)²
// the denominator terms are the numerator terms plus a non-negative remainder that is exactly
// zero for identical images, so S = 1 exactly there whatever the compiler contracts into FMAs.
enum Plane { kX, kY, kXY, kDD, kPlanes };

struct Scratch {
  int w, r, slots;
  // The products xy and d² of the source rows of the window (x and y are read from the
  // input), 2×w doubles per slot; source row q lives in slot q % slots (the reflected windows
  // of kMaxRows rows span at most `slots` consecutive source rows).
  std::vector<double> ring;
  std::vector<float> ring_xy;  // x and y of each slot's row, 2×w floats (colour images only)
  std::vector<int> ring_row;   // source row held by each slot, -1 = none
  // Vertical sums of up to kMaxRows rows, each kPlanes planes of w + 2r doubles (r mirrored
  // columns each side).
  std::vector<double> v;
  std::vector<double> s;                   // one row of the SSIM map
  std::vector<const double*> rows;         // the ring rows of the current window
  std::vector<const float*> xrows, yrows;  // the input rows of the current window
  std::vector<double> wv;                  // the weights, each repeated kMaxBlock times

  Scratch(int width, int radius)
      : w(width),
        r(radius),
        slots(2 * radius + kMaxRows),
        ring(static_cast<size_t>(slots) * 2 * width),
        ring_xy(static_cast<size_t>(slots) * 2 * width),
        ring_row(slots, -1),
        v(static_cast<size_t>(kMaxRows) * kPlanes * VStride()),
        s(width),
        rows(slots),
        xrows(slots),
        yrows(slots),
        wv(static_cast<size_t>(2 * radius + 1) * kMaxBlock) {}

  size_t VStride() const { return static_cast<size_t>(w) + 2 * r; }
  // Plane q of vertical-sum row t, at column 0.
  double* V(int t, int q) {
    return v.data() + (static_cast<size_t>(t) * kPlanes + q) * VStride() + r;
  }
  // Forgets the ring (a new channel) and splats the weights.
  void Reset(const double* wt) {
    std::fill(ring_row.begin(), ring_row.end(), -1);
    for (int k = 0; k <= 2 * r; ++k) std::fill_n(wv.begin() + k * kMaxBlock, kMaxBlock, wt[k]);
  }
};

// Points window row k at source row q: its products in the ring slot q % slots (xy at +0, d²
// at +w), computed if the slot holds another row, and its x and y samples (the input itself
// for grey images, a de-interleaved copy in the slot for colour ones).
MVTM_INLINE void WindowRow(Scratch& sc, PlanePair p, int k, int q) {
  const int slot = q % sc.slots;
  const size_t w = sc.w;
  double* out = sc.ring.data() + static_cast<size_t>(slot) * 2 * w;
  float* xy = sc.ring_xy.data() + static_cast<size_t>(slot) * 2 * w;
  const size_t row = static_cast<size_t>(q) * w;
  if (sc.ring_row[slot] != q) {
    sc.ring_row[slot] = q;
    double* __restrict oxy = out;
    double* __restrict odd = out + w;
    if (p.stride == 1) {
      const float* __restrict x = p.x + row;
      const float* __restrict y = p.y + row;
      for (size_t j = 0; j < w; ++j) {
        const double a = x[j], b = y[j], d = a - b;
        oxy[j] = a * b;
        odd[j] = d * d;
      }
    } else {
      const float* __restrict x = p.x + row * p.stride;
      const float* __restrict y = p.y + row * p.stride;
      float* __restrict cx = xy;
      float* __restrict cy = xy + w;
      const size_t stride = p.stride;
      for (size_t j = 0; j < w; ++j) {
        const float fa = x[j * stride], fb = y[j * stride];
        cx[j] = fa;
        cy[j] = fb;
        const double a = fa, b = fb, d = a - b;
        oxy[j] = a * b;
        odd[j] = d * d;
      }
    }
  }
  sc.rows[k] = out;
  sc.xrows[k] = p.stride == 1 ? p.x + row : xy;
  sc.yrows[k] = p.stride == 1 ? p.y + row : xy + w;
}

// SSIM from the filtered means ux, uy, E[xy], E[d²] (doubles or vectors of doubles).
template <typename T>
MVTM_INLINE T SsimFormula(T ux, T uy, T exy, T edd, T c1, T c2) {
  const T cov = exy - ux * uy;
  const T du = ux - uy;
  const T a1 = 2 * ux * uy + c1;
  const T a2 = 2 * cov + c2;
  const T b1 = du * du + a1;
  const T b2 = a2 + (edd - du * du);
  return (a1 * a2) / (b1 * b2);
}

// Vertical pass (scipy filters axis 0 first) of output rows i .. i+kN-1, every column, into
// sc.V(t, q), in blocks of kB columns. Each ring row loaded feeds the kN rows it belongs to,
// which divides the traffic from L2 (the ring does not fit L1). kR >= 0 fixes the radius at
// compile time (the tap loops unroll and the tap checks vanish); kR < 0 takes sc.r. The taps
// of a row are added in the same order whatever kN is.
template <int kR, int kB, int kN>
MVTM_INLINE void VerticalRows(const Job& job, PlanePair p, int i, Scratch& sc) {
  using V = typename VecOf<kB>::type;
  const int r = kR >= 0 ? kR : sc.r;
  const int taps = 2 * r + 1;
  const int span = taps + kN - 1;
  const int w = job.w;
  const size_t sw = w;
  for (int k = 0; k < span; ++k) WindowRow(sc, p, k, Reflect(i - r + k, job.h));
  const double* const* rows = sc.rows.data();
  const float* const* xrows = sc.xrows.data();
  const float* const* yrows = sc.yrows.data();
  const double* wv = sc.wv.data();
  double* out[kN][kPlanes];
  for (int t = 0; t < kN; ++t)
    for (int q = 0; q < kPlanes; ++q) out[t][q] = sc.V(t, q);
  int j = 0;
  for (; j + kB <= w; j += kB) {
    V acc[kN][kPlanes] = {};
    for (int k = 0; k < span; ++k) {
      V val[kPlanes];
      val[kX] = LoadFloats<V, kB>(xrows[k] + j);
      val[kY] = LoadFloats<V, kB>(yrows[k] + j);
      val[kXY] = Load<V>(rows[k] + j);
      val[kDD] = Load<V>(rows[k] + sw + j);
      for (int t = 0; t < kN; ++t) {
        const int tap = k - t;
        if (tap < 0 || tap >= taps) continue;
        const V wk = Load<V>(wv + tap * kMaxBlock);
        for (int q = 0; q < kPlanes; ++q) acc[t][q] += wk * val[q];
      }
    }
    for (int t = 0; t < kN; ++t)
      for (int q = 0; q < kPlanes; ++q) Store(out[t][q] + j, acc[t][q]);
  }
  for (; j < w; ++j) {
    for (int t = 0; t < kN; ++t) {
      double acc[kPlanes] = {};
      for (int k = 0; k < taps; ++k) {
        const double wk = job.wt[k];
        acc[kX] += wk * xrows[t + k][j];
        acc[kY] += wk * yrows[t + k][j];
        acc[kXY] += wk * rows[t + k][j];
        acc[kDD] += wk * rows[t + k][sw + j];
      }
      for (int q = 0; q < kPlanes; ++q) out[t][q][j] = acc[q];
    }
  }
}

// Horizontal pass of vertical-sum row t fused with the SSIM formula, into sc.s[0, w): the
// whole row, also without a map, so that a pixel's value never depends on whether its column
// falls in a vector block or in the scalar tail of a narrower range.
template <int kR, int kB>
MVTM_INLINE void HorizontalRow(const Job& job, int t, Scratch& sc) {
  using V = typename VecOf<kB>::type;
  const int r = kR >= 0 ? kR : sc.r;
  const int taps = 2 * r + 1;
  const int w = job.w;
  const double* h[kPlanes];  // h[q] + j + k is column j - r + k
  for (int q = 0; q < kPlanes; ++q) {
    double* c = sc.V(t, q);
    for (int d = 1; d <= r; ++d) {  // mirror the columns (scipy 'reflect')
      c[-d] = c[d - 1];
      c[w - 1 + d] = c[w - d];
    }
    h[q] = c - r;
  }
  const double* wv = sc.wv.data();
  double* __restrict s = sc.s.data();
  const double c1 = job.c1, c2 = job.c2;
  const V vc1 = V{} + c1, vc2 = V{} + c2;
  int j = 0;
  for (; j + kB <= w; j += kB) {
    V u[kPlanes] = {};
    for (int k = 0; k < taps; ++k) {
      const V wk = Load<V>(wv + k * kMaxBlock);
      for (int q = 0; q < kPlanes; ++q) u[q] += wk * Load<V>(h[q] + j + k);
    }
    Store(s + j, SsimFormula(u[kX], u[kY], u[kXY], u[kDD], vc1, vc2));
  }
  for (; j < w; ++j) {
    double u[kPlanes] = {};
    for (int k = 0; k < taps; ++k)
      for (int q = 0; q < kPlanes; ++q) u[q] += job.wt[k] * h[q][j + k];
    s[j] = SsimFormula(u[kX], u[kY], u[kXY], u[kDD], c1, c2);
  }
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

// Row i of the SSIM map from vertical-sum row t: its sum over the cropped columns (rows inside
// the cropped band only) into row_sum[i] and, with a map, the whole row (written when `first`,
// else added).
template <int kR, int kB>
MVTM_INLINE void FinishRow(const Job& job, int i, int t, bool first, Scratch& sc, double* row_sum) {
  const int r = kR >= 0 ? kR : job.r;
  const int w = job.w;
  HorizontalRow<kR, kB>(job, t, sc);
  const double* s = sc.s.data();
  if (i >= r && i < job.h - r) {
    const uint8_t* m = job.mask ? job.mask + static_cast<size_t>(i) * w : nullptr;
    row_sum[i] = MaskedRowSum(s, m, r, w - r);
  }
  if (job.map) {
    float* out = job.map + static_cast<size_t>(i) * w;
    if (first) {
      for (int j = 0; j < w; ++j) out[j] = static_cast<float>(s[j]);
    } else {
      for (int j = 0; j < w; ++j) out[j] += static_cast<float>(s[j]);
    }
  }
}

// Rows [row_begin, row_end) of one channel, kN at a time.
template <int kR, int kB, int kN>
MVTM_INLINE void SsimRowsImpl(const Job& job, PlanePair p, int row_begin, int row_end, bool first,
                              Scratch& sc, double* row_sum) {
  static_assert(kN <= kMaxRows && kB <= kMaxBlock, "scratch sized for kMaxRows, kMaxBlock");
  sc.Reset(job.wt);
  int i = row_begin;
  for (; i + kN <= row_end; i += kN) {
    VerticalRows<kR, kB, kN>(job, p, i, sc);
    for (int t = 0; t < kN; ++t) FinishRow<kR, kB>(job, i + t, t, first, sc, row_sum);
  }
  for (; i < row_end; ++i) {
    VerticalRows<kR, kB, 1>(job, p, i, sc);
    FinishRow<kR, kB>(job, i, 0, first, sc, row_sum);
  }
}

// Per-row sums for NCC and PSNR of one channel, samples shifted by (x0, y0) so that flat
// images give exactly zero variance and integer samples sum exactly.
enum Moment { kSx, kSy, kSxx, kSyy, kSxy, kSdd, kMoments };
using RowMoments = std::array<double, kMoments>;

MVTM_INLINE void MomentRowsImpl(const Job& job, PlanePair p, double x0, double y0, int row_begin,
                                int row_end, RowMoments* out) {
  const int w = job.w;
  for (int i = row_begin; i < row_end; ++i) {
    const size_t o = static_cast<size_t>(i) * w;
    const size_t stride = p.stride;
    const float* __restrict x = p.x + o * stride;
    const float* __restrict y = p.y + o * stride;
    const uint8_t* __restrict m = job.mask ? job.mask + o : nullptr;
    double lane[kMoments][kLanes] = {};
    int j = 0;
    for (; j + kLanes <= w; j += kLanes) {
      for (int l = 0; l < kLanes; ++l) {
        const double f = (!m || m[j + l]) ? 1.0 : 0.0;
        const double a = (x[(j + l) * stride] - x0) * f, b = (y[(j + l) * stride] - y0) * f;
        const double d = (static_cast<double>(x[(j + l) * stride]) - y[(j + l) * stride]) * f;
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
      const double a = (x[j * stride] - x0) * f, b = (y[j * stride] - y0) * f;
      const double d = (static_cast<double>(x[j * stride]) - y[j * stride]) * f;
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

// One entry point per instruction set. Block sizes: AVX-512 8 doubles × 4 rows (16 of 32
// registers hold sums), AVX2 4 × 2 (8 of 16), baseline 2 × 2 (8 of 16).
#define MVTM_SSIM_VARIANT(NAME, TARGET, KB, KN)                                               \
  TARGET void NAME(const Job& job, PlanePair p, int row_begin, int row_end, bool first,       \
                   Scratch& sc, double* row_sum) {                                            \
    if (job.r == 5) {                                                                         \
      SsimRowsImpl<5, KB, KN>(job, p, row_begin, row_end, first, sc, row_sum);                \
    } else {                                                                                  \
      SsimRowsImpl<-1, KB, KN>(job, p, row_begin, row_end, first, sc, row_sum);               \
    }                                                                                         \
  }                                                                                           \
  TARGET void NAME##Moments(const Job& job, PlanePair p, double x0, double y0, int row_begin, \
                            int row_end, RowMoments* out) {                                   \
    MomentRowsImpl(job, p, x0, y0, row_begin, row_end, out);                                  \
  }

MVTM_SSIM_VARIANT(SsimRowsBaseline, , 2, 2)
#if MVTM_X86_DISPATCH
MVTM_SSIM_VARIANT(SsimRowsAvx2, MVTM_TARGET("arch=x86-64-v3"), 4, 2)
MVTM_SSIM_VARIANT(SsimRowsAvx512, MVTM_TARGET("arch=x86-64-v4"), 8, 4)
#endif
#undef MVTM_SSIM_VARIANT

using SsimRowsFn = void (*)(const Job&, PlanePair, int, int, bool, Scratch&, double*);
using MomentRowsFn = void (*)(const Job&, PlanePair, double, double, int, int, RowMoments*);

SimdLevel BestSimdLevel() {
#if MVTM_X86_DISPATCH
  static const SimdLevel best = [] {
    __builtin_cpu_init();  // the same feature levels the kernels are compiled for
    if (__builtin_cpu_supports("x86-64-v4")) return SimdLevel::kAvx512;
    if (__builtin_cpu_supports("x86-64-v3")) return SimdLevel::kAvx2;
    return SimdLevel::kBaseline;
  }();
  return best;
#else
  return SimdLevel::kBaseline;
#endif
}

// The kernels for the requested level, capped at what the CPU offers.
void PickKernels(SimdLevel requested, SsimRowsFn* rows, MomentRowsFn* moments) {
  SimdLevel level = BestSimdLevel();
  if (requested != SimdLevel::kBest && requested < level) level = requested;
  *rows = SsimRowsBaseline;
  *moments = SsimRowsBaselineMoments;
#if MVTM_X86_DISPATCH
  if (level == SimdLevel::kAvx2) {
    *rows = SsimRowsAvx2;
    *moments = SsimRowsAvx2Moments;
  } else if (level == SimdLevel::kAvx512) {
    *rows = SsimRowsAvx512;
    *moments = SsimRowsAvx512Moments;
  }
#endif
}

// Rows are handed out in chunks from a shared counter, so a thread slowed down by other work
// on its core does not hold up the rest. Every row's values are independent of the chunking
// (the taps of a row are added in a fixed order), so results do not depend on the schedule.
constexpr int kChunkRows = 32;

// With threads = 0 (automatic), one thread per kSamplesPerThread samples, up to the cores: a
// KITTI frame (1241x376 grey, 0.47 M samples) is ~3 ms on one core, less than a scheduler time
// slice, so a second thread saves ~1 ms on an idle machine but costs several when another
// process holds the core (the pair waits for the last chunk of a descheduled worker; measured
// 4 ms on one thread against 10 ms on two on a loaded 2-core machine). Folders are compared one
// pair per thread instead (the ssim tool).
constexpr double kSamplesPerThread = 1 << 20;

int ThreadCount(int requested, int rows, double samples) {
  int t = requested > 0 ? requested : static_cast<int>(std::thread::hardware_concurrency());
  if (requested <= 0) t = std::min(t, static_cast<int>(samples / kSamplesPerThread) + 1);
  return std::clamp(t, 1, std::max(1, rows / kChunkRows));
}

// Runs fn(k) for k = 0..t-1, k = 0 on the calling thread.
template <typename Fn>
void RunThreads(int t, Fn fn) {
  std::vector<std::thread> pool;
  pool.reserve(t - 1);
  for (int k = 1; k < t; ++k) pool.emplace_back(fn, k);
  fn(0);
  for (auto& th : pool) th.join();
}

// Calls fn(begin, end) for chunks of [row_begin, row_end) taken from `next` until none is left.
template <typename Fn>
void ForEachChunk(std::atomic<int>& next, int row_begin, int row_end, Fn fn) {
  for (;;) {
    const int i0 = row_begin + next.fetch_add(1) * kChunkRows;
    if (i0 >= row_end) return;
    fn(i0, std::min(i0 + kChunkRows, row_end));
  }
}

// Throws unless a, b (and the mask) can be compared under `options`.
void CheckInputs(const Image& a, const Image& b, const SsimOptions& options, const Image* mask) {
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
}

// 1 where any channel of the mask is non-zero (empty without a mask).
std::vector<uint8_t> InsideMask(const Image* mask, size_t npix) {
  std::vector<uint8_t> inside;
  if (mask) {
    inside.assign(npix, 0);
    for (size_t q = 0; q < npix; ++q)
      for (int c = 0; c < mask->channels; ++c)
        if (mask->data[q * mask->channels + c] != 0.f) inside[q] = 1;
  }
  return inside;
}

// Pixel counts: SSIM over cropped band ∩ mask, NCC/PSNR over the mask.
void CountPixels(const std::vector<uint8_t>& inside, bool masked, int w, int h, int r,
                 Similarity& result) {
  if (masked) {
    for (size_t q = 0; q < inside.size(); ++q) result.pixels += inside[q];
    for (int i = r; i < h - r; ++i)
      for (int j = r; j < w - r; ++j) result.ssim_pixels += inside[static_cast<size_t>(i) * w + j];
  } else {
    result.pixels = static_cast<size_t>(w) * h;
    result.ssim_pixels = static_cast<size_t>(w - 2 * r) * (h - 2 * r);
  }
}

// NCC and PSNR from the per-row moments of each channel.
void NccAndPsnr(const std::vector<std::vector<RowMoments>>& moments, int h, Similarity& result) {
  const int nc = static_cast<int>(moments.size());
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
}

// Runs the SSIM kernels over rows [ssim_begin, ssim_end) into row_sum, and, when `moments` is
// not empty, the moment kernels over every row, on `threads` threads.
void RunKernels(const Job& job, const std::vector<PlanePair>& pairs, const SsimOptions& options,
                int ssim_begin, int ssim_end, std::vector<std::vector<double>>& row_sum,
                std::vector<std::vector<RowMoments>>& moments) {
  const int nc = static_cast<int>(pairs.size()), h = job.h;
  const bool with_moments = !moments.empty();
  std::vector<double> x0(nc), y0(nc);
  for (int c = 0; c < nc; ++c) {
    x0[c] = pairs[c].x[0];
    y0[c] = pairs[c].y[0];
  }
  const int t = ThreadCount(options.threads, ssim_end - ssim_begin, double(job.w) * h * nc);
  std::vector<Scratch> scratch;
  scratch.reserve(t);
  for (int k = 0; k < t; ++k) scratch.emplace_back(job.w, job.r);

  SsimRowsFn ssim_rows;
  MomentRowsFn moment_rows;
  PickKernels(options.simd, &ssim_rows, &moment_rows);
  std::atomic<int> next_ssim{0}, next_moments{0};
  RunThreads(t, [&](int k) {
    ForEachChunk(next_ssim, ssim_begin, ssim_end, [&](int i0, int i1) {
      for (int c = 0; c < nc; ++c)
        ssim_rows(job, pairs[c], i0, i1, c == 0, scratch[k], row_sum[c].data());
    });
    if (with_moments) {
      ForEachChunk(next_moments, 0, h, [&](int i0, int i1) {
        for (int c = 0; c < nc; ++c)
          moment_rows(job, pairs[c], x0[c], y0[c], i0, i1, moments[c].data());
      });
    }
  });
}

Similarity CompareImpl(const Image& a, const Image& b, const SsimOptions& options,
                       const Image* mask, Image* map, bool with_moments) {
  CheckInputs(a, b, options, mask);
  const int w = a.width, h = a.height, r = options.Radius();

  Similarity result;
  result.data_range = options.DataRangeFor(a.bits);
  const std::vector<double> wt = GaussianWeights(options.sigma, r);
  const int nc = (a.channels == 2 || a.channels == 4) ? a.channels - 1 : a.channels;

  // The colour channels, read in place from the interleaved samples.
  std::vector<PlanePair> pairs(nc);
  for (int c = 0; c < nc; ++c) pairs[c] = {a.data.data() + c, b.data.data() + c, a.channels};
  const std::vector<uint8_t> inside = InsideMask(mask, a.pixels());

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
  RunKernels(job, pairs, options, ssim_begin, ssim_end, row_sum, moments);

  if (map && nc > 1) {
    for (float& v : map->data) v /= static_cast<float>(nc);
  }
  CountPixels(inside, mask != nullptr, w, h, r, result);

  double ssim_total = 0;
  for (int c = 0; c < nc; ++c) {
    double sum = 0;
    for (int i = r; i < h - r; ++i) sum += row_sum[c][i];
    ssim_total += sum / static_cast<double>(result.ssim_pixels);
  }
  result.ssim = result.ssim_pixels ? ssim_total / nc : kNaN;

  if (with_moments) {
    NccAndPsnr(moments, h, result);
  } else {
    result.ncc = result.psnr = kNaN;
  }
  return result;
}

}  // namespace

void SsimOptions::Check() const {
  auto bad = [](const char* field, const std::string& problem, double got) {
    std::ostringstream s;
    s << problem << ", got " << got;
    throw FieldError(field, s.str());
  };
  if (!(sigma > 0) || !std::isfinite(sigma)) bad("sigma", "must be > 0", sigma);
  if (!(k1 >= 0) || !std::isfinite(k1)) bad("k1", "must be >= 0", k1);
  if (!(k2 >= 0) || !std::isfinite(k2)) bad("k2", "must be >= 0", k2);
  if (!(data_range >= 0) || !std::isfinite(data_range))
    bad("data_range", "must be > 0 (or 0 for the bit depth)", data_range);
  if (!(truncate > 0) || !std::isfinite(truncate)) bad("truncate", "must be > 0", truncate);
  if (truncate * sigma > 1000)
    bad("sigma", "the window radius truncate*sigma must be <= 1000", truncate * sigma);
  if (threads < 0) bad("threads", "must be >= 0", threads);
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
