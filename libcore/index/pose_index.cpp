#include "index/pose_index.h"

#include <flann/algorithms/dist.h>
#include <flann/algorithms/kdtree_index.h>
#include <flann/algorithms/kdtree_single_index.h>
#include <flann/general.h>

#include <Eigen/Eigenvalues>
#include <algorithm>
#include <cstdint>
#include <limits>
#include <unordered_map>

#include "base/error.h"

namespace mvtm {

namespace {

// The K best candidates so far, in CandidateBefore order (K is small: insertion into a sorted run).
class TopK {
 public:
  // Reserves no more than a small bound: --k may be far larger than the number of images.
  explicit TopK(size_t k) : k_(k) { v_.reserve(std::min<size_t>(k, 255) + 1); }
  bool full() const { return v_.size() >= k_; }
  double worst() const { return v_.back().cost; }
  void Offer(const Candidate& c) {
    if (full() && !CandidateBefore(c, v_.back())) return;
    auto it = std::upper_bound(v_.begin(), v_.end(), c, CandidateBefore);
    v_.insert(it, c);
    if (v_.size() > k_) v_.pop_back();
  }
  std::vector<Candidate>& items() { return v_; }

 private:
  size_t k_;
  std::vector<Candidate> v_;
};

}  // namespace

const char* SearchMethodName(SearchMethod m) {
  switch (m) {
    case SearchMethod::kKdTree:
      return "kdtree";
    case SearchMethod::kBrute:
      return "brute";
    case SearchMethod::kFlann:
      return "flann";
    case SearchMethod::kGrid9:
      return "grid9";
  }
  return "?";
}

std::vector<std::string> SearchMethodNames() { return {"kdtree", "brute", "flann", "grid9"}; }

SearchMethod ParseSearchMethod(const std::string& name) {
  for (SearchMethod m :
       {SearchMethod::kKdTree, SearchMethod::kBrute, SearchMethod::kFlann, SearchMethod::kGrid9})
    if (name == SearchMethodName(m)) return m;
  throw UsageError("--method: '" + name + "' is not one of kdtree, brute, flann, grid9");
}

struct PoseIndex::Impl {
  ViewSelectionOptions sel;
  PoseIndexOptions opt;
  double cos_gate = 0;
  std::vector<Eigen::Vector3d> centre, view;
  std::vector<double> flat;  // centres, x y z per candidate (FLANN's data)
  double extent = 0;         // bounding-box diagonal of the centres
  using Dist = flann::L2_Simple<double>;
  std::unique_ptr<flann::KDTreeSingleIndex<Dist>> kdtree;
  std::unique_ptr<flann::KDTreeIndex<Dist>> forest;
  // grid9
  Eigen::Vector3d up_sum = Eigen::Vector3d::Zero();  // Σ camera up vectors (world)
  Eigen::Vector3d axis_u = Eigen::Vector3d::UnitX(), axis_w = Eigen::Vector3d::UnitZ(),
                  origin = Eigen::Vector3d::Zero();
  double cell = 0;
  std::unordered_map<uint64_t, std::vector<uint32_t>> cells;
  mutable bool cache_valid = false;
  mutable uint64_t cache_key = 0;
  mutable std::vector<uint32_t> cache;

  // Scores candidate i for the query and offers it.
  void Offer(const Eigen::Vector3d& C, const Eigen::Vector3d& v, size_t i, size_t exclude,
             TopK& top) const {
    if (i == exclude) return;
    Candidate c;
    if (ScoreCandidate(C, v, centre[i], view[i], sel, cos_gate, i, c, false)) top.Offer(c);
  }

  void BuildGrid();
  uint64_t CellKey(int64_t ix, int64_t iy) const {
    return (static_cast<uint64_t>(static_cast<uint32_t>(static_cast<int32_t>(ix))) << 32) |
           static_cast<uint32_t>(static_cast<int32_t>(iy));
  }
  void CellOf(const Eigen::Vector3d& C, int64_t& ix, int64_t& iy) const {
    Eigen::Vector3d d = C - origin;
    ix = static_cast<int64_t>(std::floor(d.dot(axis_u) / cell));
    iy = static_cast<int64_t>(std::floor(d.dot(axis_w) / cell));
  }
};

// A FLANN result set that ranks by the full view-selection cost. FLANN hands it squared centre
// distances in increasing-bound order; worstDist() tells FLANN what it may prune: anything whose
// squared distance bound exceeds the K-th best cost (squared, with a rounding margin), since
// cost ≥ distance. Until K admissible candidates are held nothing is pruned.
template <class Index>  // PoseIndex::Impl (private, hence a template)
class GatedResultSet : public flann::ResultSet<double> {
 public:
  GatedResultSet(const Index& idx, const Eigen::Vector3d& C, const Eigen::Vector3d& v,
                 size_t exclude)
      : idx_(idx), C_(C), v_(v), exclude_(exclude), top_(idx.sel.k) {}
  bool full() const override { return top_.full(); }
  void addPoint(double dist_sq, size_t i) override {
    if (dist_sq > worst_sq_) return;
    idx_.Offer(C_, v_, i, exclude_, top_);
    if (top_.full()) {
      double w = top_.worst() * (1 + 1e-6) + 1e-6 * idx_.extent;
      worst_sq_ = w * w;
    }
  }
  double worstDist() const override { return worst_sq_; }
  TopK& top() { return top_; }

 private:
  const Index& idx_;
  const Eigen::Vector3d& C_;
  const Eigen::Vector3d& v_;
  size_t exclude_;
  TopK top_;
  double worst_sq_ = std::numeric_limits<double>::infinity();
};

void PoseIndex::Impl::BuildGrid() {
  const size_t n = centre.size();
  // Ground plane: the mean camera up vector (camera −y in world) is its normal.
  Eigen::Vector3d up = up_sum, mean = Eigen::Vector3d::Zero();
  for (size_t i = 0; i < n; ++i) mean += centre[i];
  mean /= static_cast<double>(n);
  origin = mean;
  Eigen::Matrix3d cov = Eigen::Matrix3d::Zero();
  for (size_t i = 0; i < n; ++i) cov += (centre[i] - mean) * (centre[i] - mean).transpose();
  if (!(up.norm() > 0.5 * static_cast<double>(n))) {  // the cameras disagree on "up"

    Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> es(cov);
    up = es.eigenvectors().col(0);
  }
  up.normalize();
  Eigen::Vector3d a = std::abs(up.x()) < 0.9 ? Eigen::Vector3d::UnitX() : Eigen::Vector3d::UnitY();
  axis_u = (a - a.dot(up) * up).normalized();
  axis_w = up.cross(axis_u);

  if (cell <= 0) {
    // The median K-th admissible cost of up to 64 evenly spaced candidates (themselves as
    // queries, excluded from their own search).
    std::vector<double> kth;
    size_t samples = std::min<size_t>(64, n);
    for (size_t s = 0; s < samples; ++s) {
      size_t q = s * n / samples;
      TopK top(sel.k);
      for (size_t i = 0; i < n; ++i) Offer(centre[q], view[q], i, q, top);
      if (!top.items().empty()) kth.push_back(top.items().back().cost);
    }
    if (!kth.empty()) {
      std::nth_element(kth.begin(), kth.begin() + static_cast<long>(kth.size() / 2), kth.end());
      cell = kth[kth.size() / 2];
    }
    if (!(cell > 0)) cell = extent > 0 ? extent / std::sqrt(static_cast<double>(n)) : 1.0;
  }
  // Keep cell indices inside int32.
  cell = std::max(cell, extent / 1e9);
  for (size_t i = 0; i < n; ++i) {
    int64_t ix, iy;
    CellOf(centre[i], ix, iy);
    cells[CellKey(ix, iy)].push_back(static_cast<uint32_t>(i));
  }
}

PoseIndex::PoseIndex(const std::vector<Rigid3d>& cands, const ViewSelectionOptions& selection,
                     const PoseIndexOptions& options)
    : impl_(std::make_unique<Impl>()) {
  Impl& m = *impl_;
  m.sel = selection;
  m.opt = options;
  m.cos_gate = HeadingGateCosine(selection);
  if (selection.k < 1) throw UsageError("k must be at least 1");
  if (cands.size() > std::numeric_limits<uint32_t>::max())
    throw Error("too many candidate poses to index");
  const size_t n = cands.size();
  m.centre.resize(n);
  m.view.resize(n);
  m.flat.resize(3 * n);
  Eigen::Vector3d lo = Eigen::Vector3d::Constant(std::numeric_limits<double>::infinity()), hi = -lo;
  for (size_t i = 0; i < n; ++i) {
    m.centre[i] = cands[i].Centre();
    m.view[i] = cands[i].ViewDirection();
    if (!m.centre[i].allFinite() || !m.view[i].allFinite())
      throw Error("candidate pose " + std::to_string(i) + " is not finite");
    for (int d = 0; d < 3; ++d) m.flat[3 * i + static_cast<size_t>(d)] = m.centre[i][d];
    lo = lo.cwiseMin(m.centre[i]);
    hi = hi.cwiseMax(m.centre[i]);
    m.up_sum += cands[i].Up();
  }
  m.extent = n ? (hi - lo).norm() : 0;
  if (n == 0) return;
  switch (options.method) {
    case SearchMethod::kBrute:
      break;
    case SearchMethod::kKdTree: {
      flann::Matrix<double> data(m.flat.data(), n, 3);
      m.kdtree = std::make_unique<flann::KDTreeSingleIndex<Impl::Dist>>(
          data, flann::KDTreeSingleIndexParams(std::max(1, options.leaf_size), true));
      m.kdtree->buildIndex();
      break;
    }
    case SearchMethod::kFlann: {
      if (options.checks < 1) throw UsageError("--checks: must be at least 1");
      flann::Matrix<double> data(m.flat.data(), n, 3);
      m.forest = std::make_unique<flann::KDTreeIndex<Impl::Dist>>(
          data, flann::KDTreeIndexParams(std::max(1, options.trees)));
      m.forest->buildIndex();
      break;
    }
    case SearchMethod::kGrid9:
      m.cell = options.grid_cell;
      m.BuildGrid();
      break;
  }
}

PoseIndex::~PoseIndex() = default;
PoseIndex::PoseIndex(PoseIndex&&) noexcept = default;
PoseIndex& PoseIndex::operator=(PoseIndex&&) noexcept = default;

size_t PoseIndex::size() const { return impl_->centre.size(); }
SearchMethod PoseIndex::method() const { return impl_->opt.method; }
double PoseIndex::grid_cell() const { return impl_->cell; }

std::vector<Candidate> PoseIndex::Select(const Rigid3d& q, size_t exclude) const {
  const Impl& m = *impl_;
  const Eigen::Vector3d C = q.Centre(), v = q.ViewDirection();
  if (!C.allFinite() || !v.allFinite()) throw Error("query pose is not finite");
  const size_t n = m.centre.size();
  std::vector<Candidate> out;
  if (n == 0) return out;
  switch (m.opt.method) {
    case SearchMethod::kBrute: {
      TopK top(m.sel.k);
      for (size_t i = 0; i < n; ++i) m.Offer(C, v, i, exclude, top);
      out = std::move(top.items());
      break;
    }
    case SearchMethod::kKdTree: {
      GatedResultSet<Impl> rs(m, C, v, exclude);
      m.kdtree->findNeighbors(rs, C.data(), flann::SearchParams(flann::FLANN_CHECKS_UNLIMITED, 0));
      out = std::move(rs.top().items());
      break;
    }
    case SearchMethod::kFlann: {
      GatedResultSet<Impl> rs(m, C, v, exclude);
      m.forest->findNeighbors(rs, C.data(), flann::SearchParams(m.opt.checks, 0));
      out = std::move(rs.top().items());
      break;
    }
    case SearchMethod::kGrid9: {
      int64_t ix, iy;
      m.CellOf(C, ix, iy);
      uint64_t key = m.CellKey(ix, iy);
      if (!m.cache_valid || m.cache_key != key) {
        // A new cell: gather the nine-way block into the cache.
        m.cache.clear();
        for (int64_t dx = -1; dx <= 1; ++dx)
          for (int64_t dy = -1; dy <= 1; ++dy) {
            auto it = m.cells.find(m.CellKey(ix + dx, iy + dy));
            if (it != m.cells.end())
              m.cache.insert(m.cache.end(), it->second.begin(), it->second.end());
          }
        m.cache_key = key;
        m.cache_valid = true;
      }
      TopK top(m.sel.k);
      for (uint32_t i : m.cache) m.Offer(C, v, i, exclude, top);
      out = std::move(top.items());
      break;
    }
  }
  for (auto& c : out) FinishCandidate(v, m.view[c.index], c);
  return out;
}

void SelectionDiff::Add(const std::vector<Candidate>& exact, const std::vector<Candidate>& approx) {
  ++queries;
  slots += exact.size();
  for (size_t r = 0; r < exact.size(); ++r) {
    bool found = std::any_of(approx.begin(), approx.end(),
                             [&](const Candidate& c) { return c.index == exact[r].index; });
    misses += !found;
    if (r >= approx.size() || approx[r].index != exact[r].index) ++wrong_rank;
    if (r < approx.size()) {
      extra_cost += approx[r].cost - exact[r].cost;
      ++filled;
    }
  }
}

}  // namespace mvtm
