// mvtm — arc-length coordinates along a recorded path (roadsplit, road streaming).
//
// A path is the polyline through camera centres in recording order. PathIndex answers "how far
// along the path is the point nearest to X" for any point (a camera, a mesh triangle), exactly:
// FLANN's exact KD-tree (flann::KDTreeSingleIndex) over samples of the polyline finds the
// nearest sample, and the point is projected on the segments around it, so the answer is exact
// wherever one stretch of the path is nearer than any other by more than half the sample step.
// A path that passes the same place twice (a loop) answers with the nearer of the two passes.
//
// Thread safety: Locate() may be called concurrently (FLANN's exact index is read-only).
#pragma once

#include <Eigen/Core>
#include <memory>
#include <vector>

namespace mvtm {

class PathIndex {
 public:
  // `points`: the polyline's vertices in order (>= 1). Samples are placed every `step` units
  // (> 0) along each segment. Consecutive equal points are allowed (a stop). Throws Error when
  // the path would need more than 5e7 samples (a pose far from the others).
  PathIndex(std::vector<Eigen::Vector3d> points, double step);
  ~PathIndex();
  PathIndex(const PathIndex&) = delete;
  PathIndex& operator=(const PathIndex&) = delete;

  // Arc length at vertex i, and the whole length.
  double ArcLength(size_t vertex) const { return s_[vertex]; }
  double Length() const { return s_.back(); }
  const std::vector<Eigen::Vector3d>& points() const { return points_; }

  struct Location {
    double s = 0;         // arc length of the nearest point
    double distance = 0;  // from the query to it
  };
  Location Locate(const Eigen::Vector3d& x) const;

 private:
  std::vector<Eigen::Vector3d> points_;
  std::vector<double> s_;
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace mvtm
