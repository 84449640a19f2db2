#include "scene/reconstruction.h"

#include <algorithm>

namespace mvtm {

const ImageRecord* Reconstruction::FindImage(const std::string& name) const {
  for (const auto& [id, im] : images)
    if (im.name == name) return &im;
  return nullptr;
}

std::vector<const ImageRecord*> Reconstruction::ImagesByName() const {
  std::vector<const ImageRecord*> v;
  for (const auto& [id, im] : images) v.push_back(&im);
  std::sort(v.begin(), v.end(),
            [](const ImageRecord* a, const ImageRecord* b) { return a->name < b->name; });
  return v;
}

}  // namespace mvtm
