#include "index/view_selection.h"

namespace mvtm {

std::vector<Candidate> SelectViews(const Rigid3d& q, const std::vector<Rigid3d>& cands,
                                   const ViewSelectionOptions& o, size_t exclude) {
  const Eigen::Vector3d C = q.Centre(), v = q.ViewDirection();
  const double cos_gate = HeadingGateCosine(o);
  std::vector<Candidate> out;
  Candidate c;
  for (size_t i = 0; i < cands.size(); ++i) {
    if (i == exclude) continue;
    if (ScoreCandidate(C, v, cands[i].Centre(), cands[i].ViewDirection(), o, cos_gate, i, c))
      out.push_back(c);
  }
  std::sort(out.begin(), out.end(), CandidateBefore);
  if (out.size() > o.k) out.resize(o.k);
  return out;
}

}  // namespace mvtm
