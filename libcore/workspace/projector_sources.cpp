#include "workspace/projector_sources.h"

#include <algorithm>

#include "base/error.h"
#include "image/mask.h"
#include "io/exposure_tsv.h"

namespace mvtm {

Image ResizeNearest(const Image& d, int w, int h) {
  if (d.width == w && d.height == h) return d;
  Image r(w, h, d.channels, d.bits);
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x) {
      int sx = std::min(d.width - 1, int((x + 0.5) * d.width / w));
      int sy = std::min(d.height - 1, int((y + 0.5) * d.height / h));
      for (int c = 0; c < d.channels; ++c) r.at(x, y, c) = d.at(sx, sy, c);
    }
  return r;
}

ProjectorSources::ProjectorSources(const Workspace& ws, const Reconstruction& rec,
                                   std::vector<const ImageRecord*> images, Renderer* renderer,
                                   bool prefer_textures, size_t capacity)
    : ws_(ws),
      rec_(rec),
      images_(std::move(images)),
      renderer_(renderer),
      prefer_textures_(prefer_textures),
      capacity_(capacity) {}

std::map<std::string, ExposureRow> ReadWorkspaceExposure(const Workspace& ws) {
  std::map<std::string, ExposureRow> by_name;
  if (fs::exists(ws.ExposurePath()))
    for (auto& row : ReadExposureTsv(ws.ExposurePath().string())) by_name[row.image] = row;
  return by_name;
}

bool ChangesSamples(const ExposureRow& e) { return float(e.gain) != 1.f || float(e.offset) != 0.f; }

bool ProjectorSources::ExposureOf(size_t k, float& gain, float& offset) {
  if (!exposure_read_) {  // on first use: a run that does not use exposure never reads the file
    exposure_read_ = true;
    exposure_ = ReadWorkspaceExposure(ws_);
  }
  auto it = exposure_.find(images_[k]->name);
  const ExposureRow e = it == exposure_.end() ? ExposureRow() : it->second;
  gain = float(e.gain);
  offset = float(e.offset);
  return ChangesSamples(e);
}

View ProjectorSources::ViewOf(size_t k) const {
  return View{rec_.cameras.at(images_[k]->camera_id), images_[k]->world_to_camera};
}

const Image& ProjectorSources::ImageOf(size_t k) {
  auto it = image_.find(k);
  if (it == image_.end()) {
    const std::string& name = images_[k]->name;
    fs::path p = prefer_textures_ ? ws_.SourceImagePath(name) : ws_.ImagePath(name);
    Image img = ReadImage(p.string());
    const Camera& cam = rec_.cameras.at(images_[k]->camera_id);
    RequireImageSize(img, p.string(), cam.width, cam.height);
    it = image_.emplace(k, std::move(img)).first;
  }
  return it->second;
}

const Image& ProjectorSources::DepthOf(size_t k) {
  auto it = depth_.find(k);
  if (it == depth_.end()) {
    View v = ViewOf(k);
    fs::path dp = ws_.DepthPath(images_[k]->name);
    Image d;
    if (fs::exists(dp)) {
      d = ResizeNearest(ReadFloatMap(dp.string()), int(v.camera.width), int(v.camera.height));
    } else {
      if (!renderer_) throw Error(dp.string(), 0, "no depth map (run bakedepth)");
      d = renderer_->RenderDepth(v);
    }
    it = depth_.emplace(k, std::move(d)).first;
  }
  return it->second;
}

const Image* ProjectorSources::MaskOf(size_t k) {
  auto it = mask_.find(k);
  if (it == mask_.end()) {
    fs::path mp = ws_.MaskPath(images_[k]->name);
    Image m = fs::exists(mp) ? ReadMask(mp.string()) : Image();
    const Camera& cam = rec_.cameras.at(images_[k]->camera_id);
    if (!m.empty()) RequireImageSize(m, mp.string(), cam.width, cam.height);
    it = mask_.emplace(k, std::move(m)).first;
  }
  return it->second.empty() ? nullptr : &it->second;
}

void ProjectorSources::Trim() {
  for (auto* cache : {&image_, &depth_, &mask_})
    if (cache->size() > capacity_) cache->clear();
}

}  // namespace mvtm
