#include "index/view_selection.h"

#include <algorithm>
#include <cmath>

namespace mvtm {

std::vector<Candidate> SelectViews(const Rigid3d& q, const std::vector<Rigid3d>& cands,
                                   const ViewSelectionOptions& o, size_t exclude) {
  const Eigen::Vector3d C = q.Centre(), v = q.ViewDirection();
  const double cos_gate = std::cos(o.max_heading_deg * M_PI / 180.0);
  std::vector<Candidate> out;
  for (size_t i = 0; i < cands.size(); ++i) {
    if (i == exclude) continue;
    Eigen::Vector3d vk = cands[i].ViewDirection();
    double c = std::clamp(v.dot(vk), -1.0, 1.0);
    if (c < cos_gate - 1e-12) continue;
    double angle = std::atan2(v.cross(vk).norm(), v.dot(vk));
    Eigen::Vector3d d = cands[i].Centre() - C;
    double dist = d.norm();
    double cost = dist + o.heading_weight * angle + o.ahead_weight * std::max(0.0, d.dot(v));
    out.push_back({i, cost, dist, angle * 180.0 / M_PI});
  }
  std::sort(out.begin(), out.end(), [](const Candidate& a, const Candidate& b) {
    return a.cost != b.cost ? a.cost < b.cost : a.index < b.index;
  });
  if (out.size() > o.k) out.resize(o.k);
  return out;
}

}  // namespace mvtm
