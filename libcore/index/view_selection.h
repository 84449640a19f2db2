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
//
// Every cost ≥ the centre distance |C_k − C|; the spatial indexes (index/pose_index.h) prune on
// that bound and score candidates with ScoreCandidate() below, the very function SelectViews
// uses, so an exact index returns bit-identical candidates.
#pragma once

#include <algorithm>
#include <cmath>
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
  size_t index;  // into the candidate list
  double cost;   // the ranking cost (metres)
  double distance;
  double heading_deg;
};

// The best min(k, admissible) candidates, best first. `exclude` (optional, may be SIZE_MAX) is
// left out (a held-out image itself).
std::vector<Candidate> SelectViews(const Rigid3d& query_w2c,
                                   const std::vector<Rigid3d>& candidates_w2c,
                                   const ViewSelectionOptions& options,
                                   size_t exclude = static_cast<size_t>(-1));

// The ranking order: cost, then index.
inline bool CandidateBefore(const Candidate& a, const Candidate& b) {
  return a.cost != b.cost ? a.cost < b.cost : a.index < b.index;
}

// The cosine below which a candidate fails the heading gate.
inline double HeadingGateCosine(const ViewSelectionOptions& o) {
  return std::cos(o.max_heading_deg * M_PI / 180.0);
}

// Scores candidate `index` (centre Ck, viewing direction vk) for a query (centre C, viewing
// direction v). Returns false when it fails the heading gate. With `need_angle` false and
// heading_weight 0, the angle (an atan2) is skipped and heading_deg left NaN: the cost is the
// same bits either way (dist + 0·angle == dist); FinishCandidate() fills it in later.
inline bool ScoreCandidate(const Eigen::Vector3d& C, const Eigen::Vector3d& v,
                           const Eigen::Vector3d& Ck, const Eigen::Vector3d& vk,
                           const ViewSelectionOptions& o, double cos_gate, size_t index,
                           Candidate& out, bool need_angle = true) {
  double c = std::clamp(v.dot(vk), -1.0, 1.0);
  if (c < cos_gate - 1e-12) return false;
  Eigen::Vector3d d = Ck - C;
  double dist = d.norm();
  double ahead = o.ahead_weight * std::max(0.0, d.dot(v));
  if (need_angle || o.heading_weight != 0) {
    double angle = std::atan2(v.cross(vk).norm(), v.dot(vk));
    out = {index, dist + o.heading_weight * angle + ahead, dist, angle * 180.0 / M_PI};
  } else {
    out = {index, dist + 0.0 + ahead, dist, std::nan("")};
  }
  return true;
}

// Fills heading_deg of a candidate scored with need_angle = false.
inline void FinishCandidate(const Eigen::Vector3d& v, const Eigen::Vector3d& vk, Candidate& c) {
  if (std::isnan(c.heading_deg))
    c.heading_deg = std::atan2(v.cross(vk).norm(), v.dot(vk)) * 180.0 / M_PI;
}

}  // namespace mvtm
