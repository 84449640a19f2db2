// mvtm — choosing projector images for a pose (shared by ptmrender, inpaint3d and pickview).
//
// The metric (thesis appendix D, with one change): a candidate is admissible when its viewing
// direction is within `max_heading_deg` of the query's (the ±45° heading gate). Admissible
// candidates are ranked by
//     cost = |C_k − C| + heading_weight · angle(k)[rad] + ahead_weight · max(0, (C_k − C)·v)
// with v the query's viewing direction. The last term is the change: a projector *ahead* of the
// query misses the near part of its view (about 30 % on KITTI), while one just behind looking the
// same way covers it, so at equal distance the one behind wins. ahead_weight = 0 gives the
// thesis's nearest-pose rule. Ties break by candidate index, so results are deterministic.
// Poses are world-to-camera (geometry/rigid.h).
#pragma once

#include <cstddef>
#include <vector>

#include "geometry/rigid.h"

namespace mvtm {

struct ViewSelectionOptions {
  size_t k = 4;                 // projectors per query
  double max_heading_deg = 45;  // heading gate
  double heading_weight = 0;    // metres per radian of heading difference
  double ahead_weight = 1.0;    // extra cost per metre the candidate is ahead of the query
};

struct Candidate {
  size_t index;   // into the candidate list
  double cost;    // the ranking cost (metres)
  double distance;
  double heading_deg;
};

// The best min(k, admissible) candidates, best first. `exclude` (optional, may be SIZE_MAX) is
// left out (a held-out image itself).
std::vector<Candidate> SelectViews(const Rigid3d& query_w2c, const std::vector<Rigid3d>& candidates_w2c,
                                   const ViewSelectionOptions& options, size_t exclude = static_cast<size_t>(-1));

}  // namespace mvtm
