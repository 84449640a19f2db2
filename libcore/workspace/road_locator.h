// mvtm — where a camera or a car is on a road (workspace/road.h): the road's recorded frames
// with their poses, and the fragment a point is in, walking the graph. Shared by ptmrender's and
// drive's routes over a road, so both place a pose in the same fragment.
//
// The fragment of a point is that of its nearest recorded frame (each fragment's own images).
// A point farther than max(overlap, half its fragment) from every recorded frame leaves the road;
// a route whose next point is nearest a fragment that is neither the one it is in nor a
// neighbour of it leaves the graph. Distances are in model units, as roadsplit measured them.
// Thread safety: const methods may be called from several threads.
#pragma once

#include <optional>
#include <string>
#include <vector>

#include "geometry/rigid.h"
#include "scene/reconstruction.h"
#include "workspace/road.h"

namespace mvtm {

struct RoadRecordedFrame {
  size_t home = 0;           // the fragment that owns it
  const ImageRecord* image;  // in models()[home]; world_to_camera as read
};

class RoadLocator {
 public:
  // Reads every fragment's sparse model (for the poses of its own images). Throws Error naming
  // the fragment.json for an owned image the model lacks, and the Graph.txt for a road that
  // owns no image.
  explicit RoadLocator(const Road& road);

  const Road& road() const { return road_; }
  // Road::RecordedFrames() order: each fragment's own images, fragments in Graph.txt's order.
  const std::vector<RoadRecordedFrame>& frames() const { return frames_; }
  // A fragment's model: its cameras and images (poses), without points (no points3D, no
  // points2D: they would grow with the road).
  const Reconstruction& model(size_t fragment) const { return models_[fragment]; }
  // A fragment's far end (SceneFarEnd of its model with the points).
  double far_end(size_t fragment) const { return far_ends_[fragment]; }

  // The fragment `centre` is in. `from`: the fragment the route was in (none for its first
  // point). Throws Error("AT is D from the nearest recorded image (NAME): it leaves the road")
  // or Error("AT leaves the graph: ...").
  size_t Locate(const Eigen::Vector3d& centre, std::optional<size_t> from,
                const std::string& at) const;

 private:
  const Road& road_;
  std::vector<Reconstruction> models_;
  std::vector<double> far_ends_;
  std::vector<RoadRecordedFrame> frames_;
  std::vector<Eigen::Vector3d> centres_;
};

}  // namespace mvtm
