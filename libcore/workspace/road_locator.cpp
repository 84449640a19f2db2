#include "workspace/road_locator.h"

#include <algorithm>
#include <limits>

#include "base/error.h"
#include "base/text.h"
#include "io/colmap_model.h"
#include "workspace/workspace.h"

namespace mvtm {

RoadLocator::RoadLocator(const Road& road) : road_(road) {
  models_.reserve(road.fragments().size());
  for (size_t k = 0; k < road.fragments().size(); ++k) {
    const RoadFragment& f = road.fragments()[k];
    models_.push_back(ReadColmapModel(Workspace(f.dir).SparseDir().string()));
    // Poses and cameras are what a route needs: the points would grow with the road.
    far_ends_.push_back(SceneFarEnd(models_.back()));
    models_.back().points3D.clear();
    for (auto& [id, im] : models_.back().images) std::vector<Point2D>().swap(im.points2D);
    for (const std::string& name : f.owned_images) {
      const ImageRecord* im = models_.back().FindImage(name);
      if (!im) throw Error(Road::RecordPath(f.dir).string(), 0, name + ": not in the model");
      frames_.push_back({k, im});
      centres_.push_back(im->world_to_camera.Centre());
    }
  }
  if (frames_.empty()) throw Error(road.GraphPath().string(), 0, "the road owns no images");
}

size_t RoadLocator::Locate(const Eigen::Vector3d& centre, std::optional<size_t> from,
                           const std::string& at) const {
  size_t best = 0;
  double best_d = std::numeric_limits<double>::infinity();
  for (size_t j = 0; j < centres_.size(); ++j) {
    const double d = (centres_[j] - centre).norm();
    if (d < best_d) best_d = d, best = j;
  }
  const size_t k = frames_[best].home;
  const RoadFragment& near = road_.fragments()[k];
  const double reach = std::max(near.overlap, (near.s_end - near.s_begin) / 2);
  if (!(best_d <= reach))
    throw Error(at + " is " + FormatDouble(best_d) + " from the nearest recorded image (" +
                frames_[best].image->name + "): it leaves the road");
  if (from && k != *from && !road_.Adjacent(*from, k))
    throw Error(at + " leaves the graph: it is nearest " + near.id + ", not " +
                road_.fragments()[*from].id + " or a neighbour of it");
  return k;
}

}  // namespace mvtm
