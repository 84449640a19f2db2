#include "index/path_index.h"

#include <flann/algorithms/dist.h>
#include <flann/algorithms/kdtree_single_index.h>
#include <flann/general.h>

#include <algorithm>
#include <cmath>
#include <limits>

#include "base/error.h"

namespace mvtm {

struct PathIndex::Impl {
  using Dist = flann::L2_Simple<double>;
  std::vector<double> flat;     // samples, x y z
  std::vector<size_t> segment;  // the segment each sample lies on
  std::unique_ptr<flann::KDTreeSingleIndex<Dist>> tree;
};

PathIndex::PathIndex(std::vector<Eigen::Vector3d> points, double step)
    : points_(std::move(points)), impl_(std::make_unique<Impl>()) {
  if (points_.empty()) throw Error("a path needs at least one point");
  if (!(step > 0)) throw Error("a path's sample step must be > 0");
  s_.assign(points_.size(), 0.0);
  for (size_t i = 1; i < points_.size(); ++i)
    s_[i] = s_[i - 1] + (points_[i] - points_[i - 1]).norm();
  if (s_.back() / step > 5e7)
    throw Error("a path of " + std::to_string(s_.back()) + " units sampled every " +
                std::to_string(step) + " would need more than 5e7 samples");
  Impl& m = *impl_;
  auto add = [&](const Eigen::Vector3d& p, size_t seg) {
    m.flat.insert(m.flat.end(), {p.x(), p.y(), p.z()});
    m.segment.push_back(seg);
  };
  add(points_[0], 0);
  for (size_t i = 0; i + 1 < points_.size(); ++i) {
    const double len = s_[i + 1] - s_[i];
    const int n = std::max(1, static_cast<int>(std::ceil(len / step)));
    for (int k = 1; k <= n; ++k)
      add(points_[i] + (points_[i + 1] - points_[i]) * (double(k) / n), i);
  }
  flann::Matrix<double> data(m.flat.data(), m.segment.size(), 3);
  m.tree = std::make_unique<flann::KDTreeSingleIndex<Impl::Dist>>(
      data, flann::KDTreeSingleIndexParams(8, true));
  m.tree->buildIndex();
}

PathIndex::~PathIndex() = default;

PathIndex::Location PathIndex::Locate(const Eigen::Vector3d& x) const {
  const Impl& m = *impl_;
  size_t nearest = 0;
  double d2 = 0;
  flann::Matrix<double> query(const_cast<double*>(x.data()), 1, 3);
  flann::Matrix<size_t> idx(&nearest, 1, 1);
  flann::Matrix<double> dist(&d2, 1, 1);
  m.tree->knnSearch(query, idx, dist, 1, flann::SearchParams(flann::FLANN_CHECKS_UNLIMITED));
  Location best{0, std::numeric_limits<double>::infinity()};
  if (points_.size() == 1) return {0, (x - points_[0]).norm()};
  // The segments on either side of the nearest sample: the nearest point of the path is on one
  // of them (a sample at a vertex belongs to the segment before it).
  const size_t seg = m.segment[nearest];
  for (size_t k = seg == 0 ? 0 : seg - 1; k <= std::min(seg + 1, points_.size() - 2); ++k) {
    const Eigen::Vector3d a = points_[k], ab = points_[k + 1] - a;
    const double len2 = ab.squaredNorm();
    const double t = len2 > 0 ? std::clamp((x - a).dot(ab) / len2, 0.0, 1.0) : 0.0;
    const double d = (x - (a + t * ab)).norm();
    if (d < best.distance) best = {s_[k] + t * (s_[k + 1] - s_[k]), d};
  }
  return best;
}

}  // namespace mvtm
