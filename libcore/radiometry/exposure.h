// mvtm — exposure between photos: a gain and an offset per image, fitted to co-visible points.
//
// Real cameras change exposure from frame to frame (KITTI's do). A surface point p of radiance
// L_p seen by image i is recorded as I = g_i · L_p + o_i (a linear camera response over the
// range in use). Given the grey values of the sparse points where the images observe them, the
// gains, offsets and radiances are fitted by alternating least squares, with observations
// further than `outlier_mads` median absolute deviations from the fit dropped (occlusions,
// specular highlights, moving objects, a point's pixel on an edge).
//
// Gauge: the model is unchanged by L → aL + c, g → g/a, o → o − g·c/a. It is fixed (by such a
// transform) so that the fitted images' gains have geometric mean 1 and their offsets mean 0:
// the common radiometric frame is the average exposure of the workspace. Images with fewer than
// `min_points` observations keep gain 1, offset 0 (and are reported as unfitted).
//
// Values are on the images' 8-bit scale (0..255). Thread safety: pure functions.
#pragma once

#include <cstddef>
#include <vector>

#include "image/image.h"
#include "scene/reconstruction.h"

namespace mvtm {

struct ExposureObservation {
  size_t image = 0;  // index into the image list
  size_t point = 0;  // index of the 3-D point
  double value = 0;  // grey value where the image sees the point, 0..255
};

struct Exposure {
  double gain = 1, offset = 0;
  bool fitted = false;  // false: too few observations, identity kept
};

struct ExposureOptions {
  bool offsets = false;       // fit offsets too (else gains only: robust to noisy samples)
  int iterations = 30;        // alternating least-squares rounds, >= 1
  double outlier_mads = 3.0;  // residuals beyond this many MADs are dropped, > 0
  size_t min_points = 20;     // observations an image needs to be fitted

  void Check() const;  // throws UsageError naming the option
};

// Fits one Exposure per image (n_images of them) to the observations.
std::vector<Exposure> FitExposure(const std::vector<ExposureObservation>& obs, size_t n_images,
                                  const ExposureOptions& options);

// The gain and offset that bring `from` closest to `to` in least squares (to ≈ gain · from +
// offset, over every sample of every channel, inside `mask` when given: any channel non-zero,
// image/mask.h). Same size and channels required (Error). A flat `from` gets gain 1.
Exposure FitImageExposure(const Image& from, const Image& to, const Image* mask = nullptr);
// gain · img + offset, clamped to the image's range (0..MaxValue()).
Image ApplyExposure(Image img, const Exposure& e);

// The grey value (bilinear, 0..255 scale) of each image at each of its points2D that has a
// 3-D point; `images` are the model's images in `order` (ReadImage, any channel count or depth),
// point indices number rec.points3D in id order. Pixels outside the image are skipped.
std::vector<ExposureObservation> ObservePoints(const Reconstruction& rec,
                                               const std::vector<const ImageRecord*>& order,
                                               const std::vector<Image>& images);

}  // namespace mvtm
