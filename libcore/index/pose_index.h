// mvtm — a spatial index over projector poses for view selection (pickview, thesis §D.2).
//
// PoseIndex answers SelectViews() queries (index/view_selection.h: heading gate, then
// cost = distance + heading and ahead terms, ties by candidate index) without scoring every
// candidate. Methods:
//   kBrute   every candidate scored: SelectViews itself over pre-computed centres.
//   kKdTree  exact. FLANN's single exact KD-tree (flann::KDTreeSingleIndex) over the camera
//            centres, searched with a result set that scores each visited centre with the full
//            metric and keeps the K best admissible ones. Since cost ≥ distance, a subtree or
//            point is pruned only when its distance bound exceeds the current K-th best cost
//            (plus a 1e-6 relative, 1e-6·extent absolute margin for rounding), so the result is
//            bit-identical to brute force, ties included. One pass: no re-search with a larger K;
//            when fewer than K candidates are admissible it degrades to visiting every centre.
//   kFlann   approximate. FLANN's randomised KD-trees (flann::KDTreeIndex, `trees` trees) with
//            the same scoring result set, stopping after `checks` leaves once K admissible
//            candidates are held. Not reproducible: FLANN 1.9 (Debian's libflann) shuffles the
//            points of each tree with a std::mt19937 seeded from std::random_device
//            (kdtree_index.h, buildIndexImpl), so two builds choose different splits and may
//            return different candidates. Use kKdTree for reproducible output.
//   kGrid9   approximate; the thesis's nine-way grid search (§D.2.1) as the historical baseline.
//            Camera centres are projected on the ground plane (normal: the mean camera up
//            vector, −y of the camera axes; the least-variance axis of the centres if the up
//            vectors disagree) and binned in square cells of side `grid_cell` (0: automatic, the
//            median K-th admissible cost of up to 64 evenly spaced candidates, i.e. a cell about
//            as wide as the distance to the K-th projector). A query scores the candidates of its
//            cell and the 8 neighbouring cells (the nine-way block); that candidate list (the
//            "subtree") is cached, and the next query reuses it without touching the grid when it
//            falls in the same cell, as consecutive poses along a trajectory do. It misses any
//            projector outside the 3×3 block and ignores height.
// Every method returns the same Candidate rows, best first, ties broken by candidate index (pass
// candidates sorted by image name to break ties by name).
//
// Thread safety: Select() on one index is not safe to call concurrently (grid9 keeps the previous
// query's cell); use one index per thread. Poses are world-to-camera (geometry/rigid.h).
#pragma once

#include <memory>
#include <string>
#include <vector>

#include "index/view_selection.h"

namespace mvtm {

enum class SearchMethod { kKdTree, kBrute, kFlann, kGrid9 };

// "kdtree", "brute", "flann", "grid9".
const char* SearchMethodName(SearchMethod m);
std::vector<std::string> SearchMethodNames();
// Throws UsageError naming the bad value and the choices.
SearchMethod ParseSearchMethod(const std::string& name);
inline bool IsExact(SearchMethod m) {
  return m == SearchMethod::kKdTree || m == SearchMethod::kBrute;
}

struct PoseIndexOptions {
  SearchMethod method = SearchMethod::kKdTree;
  int checks = 32;       // flann: leaves visited per query (more: slower, fewer misses)
  int trees = 4;         // flann: randomised trees
  int leaf_size = 8;     // kdtree: centres per leaf
  double grid_cell = 0;  // grid9: cell side in the poses' length unit; 0 = automatic
};

class PoseIndex {
 public:
  // Indexes the candidates (world-to-camera poses). Throws Error when a pose is not finite.
  PoseIndex(const std::vector<Rigid3d>& candidates_w2c, const ViewSelectionOptions& selection,
            const PoseIndexOptions& options = {});
  ~PoseIndex();
  PoseIndex(PoseIndex&&) noexcept;
  PoseIndex& operator=(PoseIndex&&) noexcept;

  size_t size() const;
  SearchMethod method() const;
  double grid_cell() const;  // grid9: the cell side in use (0 for other methods)

  // The best min(K, admissible) candidates for a query, best first; `exclude` is left out.
  std::vector<Candidate> Select(const Rigid3d& query_w2c,
                                size_t exclude = static_cast<size_t>(-1)) const;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

// How an approximate selection differs from the exact one, summed over queries.
struct SelectionDiff {
  size_t queries = 0;
  size_t slots = 0;       // exact results (rank slots)
  size_t misses = 0;      // exact results not among the approximate ones
  size_t wrong_rank = 0;  // slots where the two lists differ
  double extra_cost = 0;  // Σ over slots both lists fill of (approximate − exact) cost, ≥ 0
  size_t filled = 0;      // slots both lists fill

  void Add(const std::vector<Candidate>& exact, const std::vector<Candidate>& approx);
  double MissRate() const {
    return slots ? static_cast<double>(misses) / static_cast<double>(slots) : 0;
  }
  double MeanExtraCost() const { return filled ? extra_cost / static_cast<double>(filled) : 0; }
};

}  // namespace mvtm
