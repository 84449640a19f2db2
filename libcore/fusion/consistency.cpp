#include <tbb/parallel_for.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <string>

#include "base/error.h"
#include "fusion/fusion.h"

namespace mvtm {
namespace {

constexpr float kNoDepth = std::numeric_limits<float>::infinity();

bool Valid(float z) { return std::isfinite(z) && z > 0; }

}  // namespace

void CheckDepthView(const DepthView& v, size_t index) {
  const std::string what = "depth view " + std::to_string(index) + ": ";
  if (v.depth.channels != 1 && !v.depth.empty()) throw Error(what + "depth must have 1 channel");
  if (v.camera.width != static_cast<uint64_t>(v.depth.width) ||
      v.camera.height != static_cast<uint64_t>(v.depth.height)) {
    throw Error(what + "camera is " + std::to_string(v.camera.width) + "x" +
                std::to_string(v.camera.height) + " but depth is " + std::to_string(v.depth.width) +
                "x" + std::to_string(v.depth.height) + " (use Camera::Scaled)");
  }
  if (!v.confidence.empty() &&
      (v.confidence.width != v.depth.width || v.confidence.height != v.depth.height ||
       v.confidence.channels != 1)) {
    throw Error(what + "confidence must be 1 channel of the depth map's size");
  }
  v.camera.RequireUndistorted();
}

namespace {

// Depth of view `v` at pixel coordinates p (COLMAP convention). Inverse depth is affine in the
// image on a plane, so bilinear interpolation of 1/z is exact there; where a neighbour is
// missing the nearest pixel is used. Returns +inf outside the image or where there is no depth.
float SampleDepth(const Image& depth, const Eigen::Vector2d& p) {
  if (!(p.x() >= 0 && p.y() >= 0 && p.x() < depth.width && p.y() < depth.height)) return kNoDepth;
  const int xn = static_cast<int>(p.x()), yn = static_cast<int>(p.y());
  const double fx = p.x() - 0.5, fy = p.y() - 0.5;
  const int x0 = static_cast<int>(std::floor(fx)), y0 = static_cast<int>(std::floor(fy));
  if (x0 >= 0 && y0 >= 0 && x0 + 1 < depth.width && y0 + 1 < depth.height) {
    const float z00 = depth.at(x0, y0), z10 = depth.at(x0 + 1, y0);
    const float z01 = depth.at(x0, y0 + 1), z11 = depth.at(x0 + 1, y0 + 1);
    if (Valid(z00) && Valid(z10) && Valid(z01) && Valid(z11)) {
      const double ax = fx - x0, ay = fy - y0;
      const double inv = (1 - ay) * ((1 - ax) / z00 + ax / z10) + ay * ((1 - ax) / z01 + ax / z11);
      return static_cast<float>(1.0 / inv);
    }
  }
  const float z = depth.at(xn, yn);
  return Valid(z) ? z : kNoDepth;
}

struct ViewGeometry {
  Eigen::Matrix3d r;  // world to camera
  Eigen::Vector3d t;
};

void FilterView(const std::vector<DepthView>& views, const std::vector<ViewGeometry>& geo, size_t i,
                const ConsistencyOptions& options, Image& out) {
  const DepthView& vi = views[i];
  const Eigen::Matrix3d ri_t = geo[i].r.transpose();
  for (int y = 0; y < vi.depth.height; ++y) {
    for (int x = 0; x < vi.depth.width; ++x) {
      const float z = vi.depth.at(x, y);
      if (!Valid(z)) {
        out.at(x, y) = kNoDepth;
        continue;
      }
      const Eigen::Vector3d xc = vi.camera.Unproject({x + 0.5, y + 0.5}, z);
      const Eigen::Vector3d xw = ri_t * (xc - geo[i].t);
      int agree = 0, witnesses = 0;
      for (size_t j = 0; j < views.size() && agree < options.min_agree; ++j) {
        if (j == i) continue;
        const Eigen::Vector3d xj = geo[j].r * xw + geo[j].t;
        if (!(xj.z() > 0)) continue;
        const float zj = SampleDepth(views[j].depth, views[j].camera.Project(xj));
        if (!std::isfinite(zj)) continue;
        const double tol = options.relative_tolerance * xj.z();
        if (zj >= xj.z() - tol) ++witnesses;  // j saw this far along its ray: it could confirm
        if (std::abs(zj - xj.z()) <= tol) ++agree;
      }
      const int need = options.witnessed ? std::max(1, std::min(options.min_agree, witnesses))
                                         : options.min_agree;
      out.at(x, y) = agree >= need ? z : kNoDepth;
    }
  }
}

}  // namespace

void ConsistencyOptions::Check() const {
  if (min_agree < 1) {
    throw UsageError("min_agree must be >= 1, got " + std::to_string(min_agree));
  }
  if (!(relative_tolerance > 0 && relative_tolerance < 1)) {
    throw UsageError("relative_tolerance must be in (0, 1), got " +
                     std::to_string(relative_tolerance));
  }
}

std::vector<Image> FilterConsistentDepth(const std::vector<DepthView>& views,
                                         const ConsistencyOptions& options) {
  options.Check();
  std::vector<ViewGeometry> geo(views.size());
  for (size_t i = 0; i < views.size(); ++i) {
    CheckDepthView(views[i], i);
    geo[i] = {views[i].world_to_camera.R(), views[i].world_to_camera.t};
  }
  std::vector<Image> out(views.size());
  for (size_t i = 0; i < views.size(); ++i) {
    out[i] = Image(views[i].depth.width, views[i].depth.height, 1, 32, kNoDepth);
  }
  tbb::parallel_for(size_t{0}, views.size(),
                    [&](size_t i) { FilterView(views, geo, i, options, out[i]); });
  return out;
}

}  // namespace mvtm
