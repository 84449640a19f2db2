#include "gaze/fixation_map.h"

#include <algorithm>
#include <cmath>

#include "base/error.h"
#include "base/text.h"

namespace mvtm {

std::vector<MappedFixation> MapFixations(const std::vector<Fixation>& fixations,
                                         const ShownFrames& frames, const MeshRaycaster& mesh,
                                         const std::vector<SourceView>& views,
                                         const DepthLookup& depth,
                                         const VisibilityOptions& options) {
  if (frames.w2c.size() != frames.clock.size())
    throw Error("MapFixations: " + std::to_string(frames.clock.size()) + " frame times but " +
                std::to_string(frames.w2c.size()) + " poses");
  std::vector<MappedFixation> out;
  out.reserve(fixations.size());
  for (const Fixation& f : fixations) {
    MappedFixation m;
    m.fixation = f;
    const double middle = 0.5 * (f.start + f.end);
    const auto frame = frames.clock.FrameAt(middle);
    if (!frame)
      throw Error("a fixation at " + FormatShort(middle) +
                  " s is outside the frames' display times");
    m.frame = *frame;
    const WorldRay ray = ScreenRay(frames.render, frames.w2c[m.frame], frames.screen.width_px,
                                   frames.screen.height_px, f.x, f.y);
    if (const auto hit = mesh.Closest(ray.origin, ray.direction)) {
      m.hit = true;
      m.X = hit->point;
      m.distance = (hit->point - ray.origin).norm();
      m.sources = SourcesOf(m.X, hit->normal, ray.origin, views, mesh, depth, options);
    }
    out.push_back(std::move(m));
  }
  return out;
}

namespace {

// The class at the fixation's pixel in the nearest source photo with a label image.
std::string LabelAoi(const MappedFixation& m, const LabelLookup& labels) {
  std::vector<const SourceHit*> by_depth;
  for (const SourceHit& s : m.sources) by_depth.push_back(&s);
  std::stable_sort(by_depth.begin(), by_depth.end(),
                   [](const SourceHit* a, const SourceHit* b) { return a->depth < b->depth; });
  for (const SourceHit* s : by_depth)
    if (const Image* l = labels(s->view))
      return CamVidClassName(static_cast<int>(
          l->at(static_cast<int>(std::floor(s->u)), static_cast<int>(std::floor(s->v)))));
  return "unknown";
}

}  // namespace

void AssignAois(std::vector<MappedFixation>& mapped, const std::vector<AoiBox>& boxes,
                const LabelLookup& labels) {
  for (MappedFixation& m : mapped) {
    if (!m.hit) {
      m.aoi = "no-surface";
    } else if (!boxes.empty()) {
      m.aoi = BoxContaining(boxes, m.X);
      if (m.aoi.empty()) m.aoi = "outside";
    } else {
      m.aoi = labels ? LabelAoi(m, labels) : "surface";
    }
  }
}

}  // namespace mvtm
