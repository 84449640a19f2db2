#include "gaze/mapping.h"

#include <algorithm>
#include <cmath>
#include <limits>

#include "base/error.h"
#include "base/stats.h"

namespace mvtm {

FrameClock::FrameClock(std::vector<double> times) : times_(std::move(times)) {
  if (times_.empty()) throw Error("no frames");
  std::vector<double> dt;
  for (size_t i = 0; i < times_.size(); ++i) {
    if (!std::isfinite(times_[i])) throw Error("frame " + std::to_string(i) + ": time not finite");
    if (i && !(times_[i] > times_[i - 1]))
      throw Error("frame " + std::to_string(i) + ": display time " + std::to_string(times_[i]) +
                  " is not after the previous frame's");
    if (i) dt.push_back(times_[i] - times_[i - 1]);
  }
  last_ = dt.empty() ? std::numeric_limits<double>::infinity() : Median(dt);
}

std::optional<size_t> FrameClock::FrameAt(double t) const {
  if (!(t >= times_.front()) || !(t < end())) return std::nullopt;
  return static_cast<size_t>(std::upper_bound(times_.begin(), times_.end(), t) - times_.begin()) -
         1;
}

WorldRay ScreenRay(const Camera& render, const Rigid3d& w2c, double screen_w, double screen_h,
                   double x, double y) {
  const double u = x * static_cast<double>(render.width) / screen_w;
  const double v = y * static_cast<double>(render.height) / screen_h;
  const Eigen::Vector3d d_cam((u - render.cx()) / render.fx(), (v - render.cy()) / render.fy(), 1);
  return {w2c.Centre(), w2c.R().transpose() * d_cam};
}

namespace {

// Smallest and largest depth of the 2×2 pixel centres around (u, v), clamped to the image (NaN
// pixels skipped: then lo > hi).
void NeighbourhoodDepth(const Image& d, double u, double v, double& lo, double& hi) {
  const int x0 = static_cast<int>(std::floor(u - 0.5)), y0 = static_cast<int>(std::floor(v - 0.5));
  lo = std::numeric_limits<double>::infinity();
  hi = -lo;
  for (int dy = 0; dy < 2; ++dy)
    for (int dx = 0; dx < 2; ++dx) {
      const int x = std::clamp(x0 + dx, 0, d.width - 1), y = std::clamp(y0 + dy, 0, d.height - 1);
      const double z = d.at(x, y);
      if (std::isnan(z)) continue;
      lo = std::min(lo, z);
      hi = std::max(hi, z);
    }
}

}  // namespace

std::vector<SourceHit> SourcesOf(const Eigen::Vector3d& X, const Eigen::Vector3d& normal,
                                 const Eigen::Vector3d& viewer,
                                 const std::vector<SourceView>& views, const MeshRaycaster& mesh,
                                 const DepthLookup& depth, const VisibilityOptions& o) {
  std::vector<SourceHit> hits;
  const double side = normal.dot(viewer - X);
  for (size_t i = 0; i < views.size(); ++i) {
    const SourceView& s = views[i];
    const Eigen::Vector3d xc = s.w2c * X;
    if (!(xc.z() > 0)) continue;
    const Eigen::Vector2d px = s.camera.Project(xc);
    if (!(px.x() >= 0 && px.y() >= 0 && px.x() < static_cast<double>(s.camera.width) &&
          px.y() < static_cast<double>(s.camera.height)))
      continue;
    const Eigen::Vector3d c = s.w2c.Centre();
    if (normal.dot(c - X) * side <= 0) continue;
    SourceHit h{i, px.x(), px.y(), xc.z(), false};
    // The depth map decides where its 2×2 neighbourhood agrees; a ray where it does not.
    const Image* map = depth ? depth(i) : nullptr;
    double lo = 0, hi = 0;
    if (map) NeighbourhoodDepth(*map, px.x(), px.y(), lo, hi);
    // No finite depth around the point (NaN, or +inf "no surface" although X is on the mesh):
    // the map has nothing to say there, a ray decides.
    if (map && !(std::isfinite(lo) && lo <= hi)) map = nullptr;
    const double zt = xc.z() / (1 + o.depth_tolerance);
    if (map && zt <= lo) {
      h.by_depth = true;
    } else if (map && zt > hi) {
      continue;  // hidden by the depth map
    } else if (mesh.Occluded(c, X - c, 0, 1 - o.ray_margin)) {
      continue;
    }
    hits.push_back(h);
  }
  return hits;
}

}  // namespace mvtm
