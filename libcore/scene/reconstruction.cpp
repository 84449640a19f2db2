#include "scene/reconstruction.h"

#include <algorithm>

#include "base/error.h"

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

}  // namespace mvtm
