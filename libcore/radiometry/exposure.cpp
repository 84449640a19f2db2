#include "radiometry/exposure.h"

#include <algorithm>
#include <cmath>
#include <map>

#include "base/error.h"
#include "base/stats.h"
#include "image/mask.h"

namespace mvtm {

void ExposureOptions::Check() const {
  if (iterations < 1 || iterations > 1000) throw UsageError("--iterations: must be 1..1000");
  if (!(outlier_mads > 0 && std::isfinite(outlier_mads)))
    throw UsageError("--outlier-mads: must be > 0");
  if (min_points < 2 || min_points > 1000000) throw UsageError("--min-points: must be 2..1000000");
}

namespace {

struct State {
  std::vector<Exposure> e;
  std::vector<double> L;  // radiance per point
  std::vector<char> use;  // observation kept
};

// Radiance of each point: mean of (I − o)/g over its kept observations.
void FitRadiance(const std::vector<ExposureObservation>& obs, State& s) {
  std::vector<double> sum(s.L.size(), 0), n(s.L.size(), 0);
  for (size_t k = 0; k < obs.size(); ++k) {
    if (!s.use[k]) continue;
    const Exposure& e = s.e[obs[k].image];
    sum[obs[k].point] += (obs[k].value - e.offset) / e.gain;
    n[obs[k].point] += 1;
  }
  for (size_t p = 0; p < s.L.size(); ++p) s.L[p] = n[p] > 0 ? sum[p] / n[p] : 0;
}

// Per image, least squares of I on L: I = g·L + o (or I = g·L).
void FitImages(const std::vector<ExposureObservation>& obs, const ExposureOptions& o, State& s) {
  const size_t n = s.e.size();
  std::vector<double> sx(n, 0), sy(n, 0), sxx(n, 0), sxy(n, 0), c(n, 0);
  for (size_t k = 0; k < obs.size(); ++k) {
    if (!s.use[k]) continue;
    const size_t i = obs[k].image;
    const double x = s.L[obs[k].point], y = obs[k].value;
    sx[i] += x, sy[i] += y, sxx[i] += x * x, sxy[i] += x * y, c[i] += 1;
  }
  for (size_t i = 0; i < n; ++i) {
    Exposure& e = s.e[i];
    e.fitted = c[i] >= double(o.min_points);
    if (!e.fitted) continue;
    if (o.offsets) {
      const double den = c[i] * sxx[i] - sx[i] * sx[i];
      if (!(den > 1e-9 * c[i] * sxx[i])) continue;  // every point of the same radiance: keep
      e.gain = (c[i] * sxy[i] - sx[i] * sy[i]) / den;
      e.offset = (sy[i] - e.gain * sx[i]) / c[i];
    } else if (sxx[i] > 0) {
      e.gain = sxy[i] / sxx[i];
    }
    if (!(e.gain > 1e-3) || !std::isfinite(e.offset)) e.gain = 1, e.offset = 0, e.fitted = false;
  }
}

// Gauge: geometric mean gain 1 and mean offset 0 over the fitted images, by the transform that
// leaves the model unchanged (L → aL + c, g → g/a, o → o − g·c/a); radiances follow on refit.
void FixGauge(State& s) {
  double log_g = 0, off = 0, gain = 0;
  size_t n = 0;
  for (const auto& e : s.e)
    if (e.fitted) log_g += std::log(e.gain), off += e.offset, gain += e.gain, ++n;
  if (n == 0) return;
  const double a = std::exp(log_g / double(n)), c_over_a = off / gain;  // mean(o) / mean(g)
  for (auto& e : s.e)
    if (e.fitted) e.offset -= e.gain * c_over_a, e.gain /= a;
}

// Drops observations whose residual is beyond outlier_mads MADs of all residuals.
void DropOutliers(const std::vector<ExposureObservation>& obs, const ExposureOptions& o, State& s) {
  std::vector<double> r(obs.size());
  for (size_t k = 0; k < obs.size(); ++k) {
    const Exposure& e = s.e[obs[k].image];
    r[k] = std::abs(obs[k].value - (e.gain * s.L[obs[k].point] + e.offset));
  }
  const double mad = std::max(Median(r), 0.5);  // at least half a grey level
  for (size_t k = 0; k < obs.size(); ++k) s.use[k] = r[k] <= o.outlier_mads * 1.4826 * mad;
}

}  // namespace

std::vector<Exposure> FitExposure(const std::vector<ExposureObservation>& obs, size_t n_images,
                                  const ExposureOptions& o) {
  o.Check();
  size_t n_points = 0;
  for (const auto& x : obs) {
    if (x.image >= n_images)
      throw Error("exposure: observation of image " + std::to_string(x.image) + " out of range");
    n_points = std::max(n_points, x.point + 1);
  }
  State s{std::vector<Exposure>(n_images), std::vector<double>(n_points, 0),
          std::vector<char>(obs.size(), 1)};
  for (int it = 0; it < o.iterations; ++it) {
    FitRadiance(obs, s);
    FitImages(obs, o, s);
    FixGauge(s);
    if (it == o.iterations / 2) {  // once the fit has settled: drop the outliers, then refit
      FitRadiance(obs, s);
      DropOutliers(obs, o, s);
    }
  }
  return s.e;
}

Exposure FitImageExposure(const Image& from, const Image& to, const Image* mask) {
  if (from.width != to.width || from.height != to.height || from.channels != to.channels)
    throw Error("exposure fit: the images differ in size or channels");
  if (mask && (mask->width != from.width || mask->height != from.height))
    throw Error("exposure fit: the mask differs in size");
  double sx = 0, sy = 0, sxx = 0, sxy = 0, n = 0;
  const size_t c = size_t(from.channels);
  const Image inside = mask ? MaskFromImage(*mask) : Image();
  for (size_t p = 0; p < from.pixels(); ++p) {
    if (mask && inside.data[p] == 0) continue;
    for (size_t k = 0; k < c; ++k) {
      const double x = from.data[p * c + k], y = to.data[p * c + k];
      sx += x, sy += y, sxx += x * x, sxy += x * y, n += 1;
    }
  }
  Exposure e;
  const double den = n * sxx - sx * sx;
  if (n < 2 || !(den > 1e-12 * n * sxx)) return e;  // flat: nothing to scale
  e.gain = (n * sxy - sx * sy) / den;
  e.offset = (sy - e.gain * sx) / n;
  e.fitted = true;
  return e;
}

Image ApplyExposure(Image img, const Exposure& e) {
  const float hi = float(img.MaxValue());
  for (float& v : img.data) v = std::clamp(float(e.gain * v + e.offset), 0.f, hi);
  return img;
}

std::vector<ExposureObservation> ObservePoints(const Reconstruction& rec,
                                               const std::vector<const ImageRecord*>& order,
                                               const std::vector<Image>& images) {
  if (order.size() != images.size()) throw Error("exposure: one image per model image is needed");
  std::map<uint64_t, size_t> point_index;
  for (const auto& [id, p] : rec.points3D) point_index.emplace(id, point_index.size());
  std::vector<ExposureObservation> obs;
  for (size_t i = 0; i < order.size(); ++i) {
    const Image grey = images[i].channels == 1 ? images[i] : ToGrey(images[i]);
    const double scale = 255.0 / grey.MaxValue();
    for (const auto& p2 : order[i]->points2D) {
      auto it = point_index.find(p2.point3D_id);
      if (it == point_index.end()) continue;
      const double x = p2.xy.x() - 0.5, y = p2.xy.y() - 0.5;  // COLMAP pixel centres at +0.5
      const int x0 = int(std::floor(x)), y0 = int(std::floor(y));
      if (x0 < 0 || y0 < 0 || x0 + 1 >= grey.width || y0 + 1 >= grey.height) continue;
      const double fx = x - x0, fy = y - y0;
      const double v = (1 - fy) * ((1 - fx) * grey.at(x0, y0) + fx * grey.at(x0 + 1, y0)) +
                       fy * ((1 - fx) * grey.at(x0, y0 + 1) + fx * grey.at(x0 + 1, y0 + 1));
      obs.push_back({i, it->second, v * scale});
    }
  }
  return obs;
}

}  // namespace mvtm
