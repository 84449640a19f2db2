#include "workspace/projector_sources.h"

#include <algorithm>
#include <chrono>

#include "base/error.h"
#include "image/mask.h"
#include "io/exposure_tsv.h"

namespace mvtm {

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

bool ProjectorSources::ExposureOf(size_t k, CameraExposure& exposure) {
  if (!exposure_read_) {  // on first use: a run that does not use exposure never reads the file
    exposure_read_ = true;
    exposure_ = ReadWorkspaceExposure(ws_);
  }
  auto it = exposure_.find(images_[k]->name);
  const ExposureRow e = it == exposure_.end() ? ExposureRow() : it->second;
  exposure = CameraExposure{float(e.gain), float(e.offset)};
  return ChangesSamples(e);
}

View ProjectorSources::ViewOf(size_t k) const {
  return View{rec_.cameras.at(images_[k]->camera_id), images_[k]->world_to_camera};
}

Image ProjectorSources::ReadColour(size_t k) const {
  return ReadSourceImage(ws_, images_[k]->name, rec_.cameras.at(images_[k]->camera_id),
                         prefer_textures_);
}

Image ProjectorSources::ReadDepthFile(size_t k) const {
  return ReadDepthAtCamera(ws_, images_[k]->name, rec_.cameras.at(images_[k]->camera_id));
}

Image ProjectorSources::ReadMaskFile(size_t k) const {
  return ReadMaskAtCamera(ws_, images_[k]->name, rec_.cameras.at(images_[k]->camera_id));
}

Image ProjectorSources::ReadSeenFile(size_t k) const {
  return ReadSeenDepthAtCamera(ws_, images_[k]->name, rec_.cameras.at(images_[k]->camera_id));
}

void ProjectorSources::TakePrefetched() {
  if (!prefetch_.valid()) return;
  std::array<Batch, 4> got = prefetch_.get();
  for (size_t i = 0; i < got.size(); ++i) prefetched_[i].merge(got[i]);
}

const Image& ProjectorSources::Get(Cache& cache, Batch& prefetched, size_t k,
                                   Image (ProjectorSources::*read)(size_t) const) {
  TakePrefetched();
  auto it = cache.find(k);
  if (it == cache.end()) {
    Image img;
    auto p = prefetched.find(k);
    if (p != prefetched.end()) {
      Read r = std::move(p->second);
      prefetched.erase(p);
      if (r.error) std::rethrow_exception(r.error);
      img = std::move(r.image);
    } else {
      img = (this->*read)(k);
    }
    it = cache.emplace(k, Entry{std::move(img), 0}).first;
  }
  it->second.used = ++tick_;
  return it->second.image;
}

const Image& ProjectorSources::ImageOf(size_t k) {
  return Get(image_, prefetched_[0], k, &ProjectorSources::ReadColour);
}

const Image& ProjectorSources::DepthOf(size_t k) {
  const Image& d = Get(depth_, prefetched_[1], k, &ProjectorSources::ReadDepthFile);
  if (!d.empty()) return d;
  if (!renderer_)
    throw Error(ws_.DepthPath(images_[k]->name).string(), 0, "no depth map (run bakedepth)");
  Image& slot = depth_[k].image;
  slot = renderer_->RenderDepth(ViewOf(k));
  return slot;
}

const Image* ProjectorSources::MaskOf(size_t k) {
  const Image& m = Get(mask_, prefetched_[2], k, &ProjectorSources::ReadMaskFile);
  return m.empty() ? nullptr : &m;
}

const Image* ProjectorSources::SeenOf(size_t k) {
  const Image& m = Get(seen_, prefetched_[3], k, &ProjectorSources::ReadSeenFile);
  return m.empty() ? nullptr : &m;
}

void ProjectorSources::Prefetch(const std::vector<size_t>& ks, bool depth, bool mask, int seen) {
  TakePrefetched();
  std::array<std::vector<size_t>, 4> todo;
  auto want = [&](size_t i, const Cache& cache, size_t k) {
    if (!cache.count(k) && !prefetched_[i].count(k)) todo[i].push_back(k);
  };
  for (size_t j = 0; j < ks.size(); ++j) {
    const size_t k = ks[j];
    want(0, image_, k);
    if (depth) want(1, depth_, k);
    if (mask) want(2, mask_, k);
    if (static_cast<int>(j) < seen) want(3, seen_, k);
  }
  if (std::all_of(todo.begin(), todo.end(), [](const auto& t) { return t.empty(); })) return;
  prefetch_ = std::async(std::launch::async, [this, todo] {
    const std::array<Image (ProjectorSources::*)(size_t) const, 4> read = {
        &ProjectorSources::ReadColour, &ProjectorSources::ReadDepthFile,
        &ProjectorSources::ReadMaskFile, &ProjectorSources::ReadSeenFile};
    std::array<Batch, 4> out;
    for (size_t i = 0; i < todo.size(); ++i)
      for (size_t k : todo[i]) try {
          out[i][k].image = (this->*read[i])(k);
        } catch (...) {
          out[i][k].error = std::current_exception();
        }
    return out;
  });
}

ProjectorSources::~ProjectorSources() {
  if (prefetch_.valid()) prefetch_.wait();
}

// Drops the least recently used items of each cache beyond the capacity.
void ProjectorSources::Trim() {
  for (Cache* cache : {&image_, &depth_, &mask_, &seen_}) {
    if (cache->size() <= capacity_) continue;
    std::vector<uint64_t> used;
    for (const auto& [k, e] : *cache) used.push_back(e.used);
    std::nth_element(used.begin(), used.end() - static_cast<std::ptrdiff_t>(capacity_), used.end());
    const uint64_t keep_from = *(used.end() - static_cast<std::ptrdiff_t>(capacity_));
    for (auto it = cache->begin(); it != cache->end();)
      it = it->second.used < keep_from ? cache->erase(it) : std::next(it);
  }
}

std::vector<Projector> GatherProjectors(ProjectorSources& sources,
                                        const std::vector<size_t>& indices, const EffectsPlan& plan,
                                        double* depth_ms) {
  std::vector<Projector> ps;
  for (size_t k : indices) {
    Projector p;
    p.view = sources.ViewOf(k);
    p.image = &sources.ImageOf(k);
    p.key = static_cast<int64_t>(k);
    if (plan.occlusion || plan.skybox) {
      const auto t0 = std::chrono::steady_clock::now();
      p.depth = &sources.DepthOf(k);
      if (depth_ms)
        *depth_ms +=
            std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0)
                .count();
    }
    if (plan.masks) p.mask = sources.MaskOf(k);
    if (static_cast<int>(ps.size()) < plan.SeenProjectors())
      p.seen = sources.SeenOf(k);  // only the projectors searched
    if (plan.exposure) sources.ExposureOf(k, p.exposure);
    ps.push_back(p);
  }
  return ps;
}

CameraExposure ExposureNear(const std::vector<Projector>& ps, const Eigen::Vector3d& centre) {
  double sw = 0, g = 0, off = 0;
  for (const Projector& p : ps) {
    const double d2 = (p.view.world_to_camera.Centre() - centre).squaredNorm();
    if (d2 == 0) return p.exposure;
    sw += 1 / d2;
    g += p.exposure.gain / d2;
    off += p.exposure.offset / d2;
  }
  if (sw == 0) return CameraExposure();
  return CameraExposure{float(g / sw), float(off / sw)};
}

std::string FirstMaskedImage(const Workspace& ws, const std::vector<const ImageRecord*>& images,
                             const std::set<size_t>& used) {
  for (size_t i : used) {
    const fs::path mp = ws.MaskPath(images[i]->name);
    if (fs::exists(mp) && CountSet(ReadMask(mp.string())) > 0) return mp.filename().string();
  }
  return "";
}

std::string FirstSeenImage(const Workspace& ws, const std::vector<const ImageRecord*>& images,
                           const std::set<size_t>& used) {
  for (size_t i : used)
    if (fs::exists(ws.StereoDepthPath(images[i]->name))) return images[i]->name;
  return "";
}

std::string FirstExposedImage(const Workspace& ws, const std::vector<const ImageRecord*>& images,
                              const std::set<size_t>& used) {
  const std::map<std::string, ExposureRow> rows = ReadWorkspaceExposure(ws);
  for (size_t i : used) {
    auto it = rows.find(images[i]->name);
    if (it != rows.end() && ChangesSamples(it->second)) return it->first;
  }
  return "";
}

}  // namespace mvtm
