#include "scene/reconstruction.h"

#include <algorithm>
#include <cmath>

#include "base/error.h"
#include "base/stats.h"

namespace mvtm {

const ImageRecord* Reconstruction::FindImage(const std::string& name) const {
  for (const auto& [id, im] : images)
    if (im.name == name) return &im;
  return nullptr;
}

Camera Reconstruction::RenderCamera(uint64_t width, uint64_t height) const {
  if (cameras.empty()) throw Error("the model has no cameras");
  Camera cam = cameras.begin()->second;
  cam.RequireUndistorted();
  return width > 0 && height > 0 ? cam.Scaled(width, height) : cam;
}

std::vector<const ImageRecord*> Reconstruction::ImagesByName() const {
  std::vector<const ImageRecord*> v;
  for (const auto& [id, im] : images) v.push_back(&im);
  std::sort(v.begin(), v.end(),
            [](const ImageRecord* a, const ImageRecord* b) { return a->name < b->name; });
  return v;
}

double ObservedDistanceQuantile(const Reconstruction& rec, double q) {
  std::vector<double> z;
  for (const auto& [id, p] : rec.points3D)
    for (const TrackElement& e : p.track) {
      auto im = rec.images.find(e.image_id);
      if (im == rec.images.end()) continue;
      const Eigen::Vector3d x = im->second.world_to_camera * p.xyz;
      const double d = x.norm();
      if (x.z() > 0 && std::isfinite(d)) z.push_back(d);
    }
  return z.empty() ? 0.0 : Percentile(std::move(z), q >= 0 ? std::min(q, 1.0) : 0.0);
}

}  // namespace mvtm
