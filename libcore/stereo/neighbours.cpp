#include "stereo/neighbours.h"

#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>

#include "base/error.h"
#include "base/stats.h"

namespace mvtm {

void NeighbourOptions::Check() const {
  if (count < 1 || count > 16) throw FieldError("count", "must be 1..16");
  if (!(min_baseline >= 0 && min_baseline < 10))
    throw FieldError("min_baseline", "must be in [0, 10)");
  if (!(max_angle_deg > 0 && max_angle_deg <= 90))
    throw FieldError("max_angle_deg", "must be in (0, 90]");
  if (!(min_coverage >= 0 && min_coverage <= 1))
    throw FieldError("min_coverage", "must be in [0, 1]");
}

double MedianSpacing(const std::vector<Rigid3d>& w2c) {
  std::vector<double> d;
  for (size_t i = 1; i < w2c.size(); ++i)
    d.push_back((w2c[i].Centre() - w2c[i - 1].Centre()).norm());
  return d.empty() ? 0 : Median(std::move(d));
}

namespace {

// Share of the points that project inside the camera's image, in front of it.
double Coverage(const Rigid3d& w2c, const Camera& cam, const std::vector<Eigen::Vector3d>& pts) {
  size_t in = 0;
  for (const auto& X : pts) {
    const Eigen::Vector3d x = w2c * X;
    if (x.z() <= 0) continue;
    const Eigen::Vector2d uv = cam.Project(x);
    in += uv.x() >= 0 && uv.y() >= 0 && uv.x() < double(cam.width) && uv.y() < double(cam.height);
  }
  return pts.empty() ? 1.0 : double(in) / double(pts.size());
}

}  // namespace

namespace {

ViewSelectionOptions CandidateSelection(const NeighbourOptions& o) {
  ViewSelectionOptions sel;
  sel.k = size_t(std::max(4 * o.count, o.count + 8));
  sel.max_heading_deg = o.max_angle_deg;
  sel.ahead_weight = 0;  // pure distance: both sides are wanted
  return sel;
}

}  // namespace

StereoNeighbourFinder::StereoNeighbourFinder(const std::vector<Rigid3d>& w2c,
                                             const std::vector<Camera>& cameras,
                                             const NeighbourOptions& o)
    : w2c_(w2c),
      cameras_(cameras),
      o_(o),
      min_base_(o.min_baseline * MedianSpacing(w2c)),
      index_(w2c, CandidateSelection(o)) {}

std::vector<size_t> StereoNeighbourFinder::Select(
    size_t i, const std::vector<Eigen::Vector3d>& ref_points) const {
  const Eigen::Vector3d ci = w2c_[i].Centre(), zi = w2c_[i].R().row(2).transpose();
  // Candidates: the nearest camera centres within the angle gate, from the pose index (any
  // image of the model: a second drive along the same road is as good a neighbour as the
  // frames before and after), nearest first.
  std::vector<Candidate> sides[2];  // 0: behind the reference, 1: ahead of it
  for (const Candidate& c : index_.Select(w2c_[i], i)) {
    if (!(c.distance > min_base_) || c.distance == 0) continue;  // no baseline: planes map alike
    const Rigid3d& p = w2c_[c.index];
    if (!ref_points.empty() && Coverage(p, cameras_[c.index], ref_points) < o_.min_coverage)
      continue;
    sides[(p.Centre() - ci).dot(zi) > 0 ? 1 : 0].push_back(c);
  }
  // Alternately from either side, nearest first: a forward-moving camera's neighbours behind
  // it see what it sees smaller, those ahead see the far scene larger; both together cover
  // occlusions either way. A side that runs out leaves the rest to the other.
  std::vector<size_t> out;
  size_t next[2] = {0, 0};
  int side = -1;
  while (int(out.size()) < o_.count && (next[0] < sides[0].size() || next[1] < sides[1].size())) {
    if (next[0] >= sides[0].size())
      side = 1;
    else if (next[1] >= sides[1].size())
      side = 0;
    else if (side < 0)  // the nearest of all first
      side = sides[1][next[1]].distance < sides[0][next[0]].distance ? 1 : 0;
    else
      side = 1 - side;
    out.push_back(sides[side][next[side]++].index);
  }
  return out;
}

std::vector<size_t> SelectStereoNeighbours(const std::vector<Rigid3d>& w2c,
                                           const std::vector<Camera>& cameras, size_t i,
                                           const std::vector<Eigen::Vector3d>& ref_points,
                                           const NeighbourOptions& o) {
  return StereoNeighbourFinder(w2c, cameras, o).Select(i, ref_points);
}

void DriveAxes(const std::vector<Rigid3d>& w2c, Eigen::Vector3d& down, Eigen::Vector3d& side) {
  down = -UpSum(w2c);
  down = down.norm() > 0 ? down.normalized() : Eigen::Vector3d::UnitY();
  Eigen::Vector3d travel = Eigen::Vector3d::Zero();
  if (w2c.size() > 1) travel = w2c.back().Centre() - w2c.front().Centre();
  if (travel.norm() == 0 && !w2c.empty()) travel = w2c.front().R().row(2).transpose();  // forward
  side = down.cross(travel);
  if (side.norm() < 1e-12)
    side = w2c.empty() ? Eigen::Vector3d::UnitX()
                       : Eigen::Vector3d(w2c.front().R().row(0).transpose());
  side.normalize();
}

std::vector<SweepFamily> SweepFamiliesFor(const Rigid3d& ref,
                                          const std::vector<Eigen::Vector3d>& pts,
                                          const Eigen::Vector3d& down_world,
                                          const Eigen::Vector3d& side_world, int planes) {
  std::vector<double> z, g, s;
  const Eigen::Matrix3d R = ref.R();
  const Eigen::Vector3d n_ground = R * down_world, n_side = R * side_world;
  for (const auto& X : pts) {
    const Eigen::Vector3d x = ref * X;
    if (!(x.z() > 0)) continue;
    z.push_back(x.z());
    g.push_back(n_ground.dot(x));
    s.push_back(n_side.dot(x));
  }
  std::vector<SweepFamily> out;
  if (z.size() < 3) return out;
  const double near_z = 0.7 * Percentile(z, 0.02), far_z = 1.5 * Percentile(z, 0.98);
  out.push_back(MakeFrontoSweep(near_z, std::max(far_z, 1.01 * near_z), planes));
  // Ground planes lie below the camera: positive offsets along "down".
  const double g_hi = 1.2 * Percentile(g, 0.98), g_lo = std::max(0.2 * g_hi, Percentile(g, 0.5));
  if (g_hi > 0 && g_hi > g_lo)
    out.push_back(MakeOffsetSweep("ground", n_ground, g_lo, g_hi, planes));
  const double s_lo = 1.2 * Percentile(s, 0.02), s_hi = 1.2 * Percentile(s, 0.98);
  if (s_hi > s_lo) out.push_back(MakeOffsetSweep("facade", n_side, s_lo, s_hi, planes));
  return out;
}

}  // namespace mvtm
