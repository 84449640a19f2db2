// mvtm — image similarity: SSIM (Wang et al. 2004), zero-mean NCC (thesis §4.1.2) and PSNR.
//
// Conventions (the contract the `ssim` tool and its man page repeat):
//  * SSIM equals scikit-image 0.19 `structural_similarity(a, b, gaussian_weights=True,
//    sigma=1.5, use_sample_covariance=False, data_range=R)` (to ~1e-15 in practice):
//      - window: a Gaussian of standard deviation `sigma`, radius r = int(truncate*sigma + 0.5)
//        (truncate 3.5, so 11×11 taps for sigma 1.5), weights exp(-x²/2σ²) normalised to sum 1
//        (scipy.ndimage._gaussian_kernel1d), applied separably, rows (axis 0) first;
//      - borders: scipy.ndimage mode 'reflect' (half-sample symmetric: d c b a | a b c d);
//      - population (co)variances σx² = E[x²] − E[x]², σxy = E[xy] − E[x]E[y];
//      - C1 = (k1·R)², C2 = (k2·R)²,
//        S = (2µxµy + C1)(2σxy + C2) / ((µx² + µy² + C1)(σx² + σy² + C2)),
//        evaluated from E[x], E[y], E[xy] and E[(x−y)²] (four filtered planes, so identical
//        images give S = 1 exactly);
//      - mean SSIM = mean of S over the image with r pixels cropped from every border
//        (skimage `crop(S, pad)`); an image with a side smaller than 2r+1 is an Error.
//  * Samples are in file scale (see image.h). R defaults to the bit depth of `a`: 255 (8-bit),
//    65535 (16-bit), 1.0 (float). scikit-image 0.19 would use 2.0 for float arrays; pass
//    `data_range` explicitly to compare float images with it.
//  * Colour: each colour channel is compared on its own and the results are averaged (skimage
//    `channel_axis=-1`). An alpha channel (2 or 4 channels) is ignored.
//  * NCC = Σ(a−ā)(b−b̄) / sqrt(Σ(a−ā)² Σ(b−b̄)²) over all evaluated pixels of a channel, averaged
//    over colour channels; NaN when a channel of either image has zero variance there.
//    PSNR = 10·log10(R² / MSE), MSE over all evaluated colour samples; +inf when MSE is 0.
//  * Mask (optional; same width and height; a pixel is inside when any of its channels is
//    nonzero): NCC and PSNR use the pixels inside the mask; mean SSIM averages the SSIM map over
//    the pixels inside the mask *and* inside the cropped region. The SSIM map itself is always
//    computed from the whole images (the window sees pixels outside the mask). A metric with no
//    pixel to average is NaN (never an error): e.g. an empty mask, or a mask whose only pixels
//    lie in the cropped border strip.
//  * The SSIM map (optional) is one float channel over the whole image, border strip included:
//    the per-channel maps averaged over colour channels; its mean over the evaluated pixels is
//    the mean SSIM.
//  * Arithmetic is double throughout (samples are converted exactly). Rows are split over
//    `threads` std::threads; results are bit-identical for any thread count (per-row partial
//    sums are added in row order). The kernels are vectorised for AVX-512, AVX2+FMA or baseline
//    x86-64, chosen at run time; the levels agree to ~1e-15, not bit for bit.
//
// Thread safety: the functions are reentrant; they start and join their own threads.
#pragma once

#include <cstddef>
#include <string>
#include <vector>

#include "base/error.h"
#include "image/image.h"

namespace mvtm {

// Thrown when two images (or an image and its mask) differ in width, height or channel count.
// The ssim tool maps it to its own exit status.
class SizeMismatchError : public Error {
 public:
  using Error::Error;
};

// Instruction sets of the SSIM kernels (x86-64; other CPUs have only the baseline).
enum class SimdLevel { kBest, kBaseline, kAvx2, kAvx512 };

struct SsimOptions {
  double sigma = 1.5;     // Gaussian window standard deviation in pixels, > 0
  double k1 = 0.01;       // luminance constant, C1 = (k1·R)², >= 0
  double k2 = 0.03;       // contrast constant, C2 = (k2·R)², >= 0
  double data_range = 0;  // R; 0 = from the bit depth of the first image (255, 65535, 1.0)
  double truncate = 3.5;  // window radius in sigmas (skimage uses 3.5 for Gaussian SSIM)
  int threads = 0;        // worker threads; 0 = automatic: one per 2^20 samples, up to the cores
  // Highest instruction set the kernels may use (capped at what the CPU has). kBest for real
  // work; the others exist for tests and benchmarks. Levels agree to ~1e-15.
  SimdLevel simd = SimdLevel::kBest;

  // Throws UsageError naming the bad value and the allowed range.
  void Check() const;
  // r = int(truncate*sigma + 0.5); the window is (2r+1)×(2r+1).
  int Radius() const;
  // R for an image of `bits` (8, 16, 32) unless data_range is set.
  double DataRangeFor(int bits) const;
};

struct Similarity {
  double ssim = 0;         // mean SSIM (NaN when ssim_pixels == 0)
  double ncc = 0;          // zero-mean NCC (NaN when undefined)
  double psnr = 0;         // dB (+inf for identical images, NaN when pixels == 0)
  size_t ssim_pixels = 0;  // pixels averaged for SSIM (cropped region ∩ mask)
  size_t pixels = 0;       // pixels used for NCC and PSNR (mask, or all)
  double data_range = 0;   // the R used
};

// Compares `a` with `b` (same size, channel count and bit depth, else SizeMismatchError for
// size/channels and Error for depth). `mask` may be null (every pixel). When `map` is not null
// it receives the SSIM map (width×height, 1 channel, bits 32). Throws Error when an image is
// smaller than the window, UsageError when options.Check() fails.
Similarity Compare(const Image& a, const Image& b, const SsimOptions& options,
                   const Image* mask = nullptr, Image* map = nullptr);

// Mean SSIM only (same rules as Compare, NCC and PSNR skipped).
double Ssim(const Image& a, const Image& b, const SsimOptions& options, const Image* mask = nullptr,
            Image* map = nullptr);

// The 2r+1 normalised Gaussian weights scipy.ndimage uses for (sigma, radius).
std::vector<double> GaussianWeights(double sigma, int radius);

}  // namespace mvtm
