#include "geometry/interpolate.h"

#include <algorithm>

#include "base/error.h"

namespace mvtm {

size_t SortKeyframes(std::vector<StampedPose>& keys, const std::string& source) {
  size_t out_of_order = 0;
  for (size_t i = 1; i < keys.size(); ++i)
    if (keys[i].time < keys[i - 1].time) ++out_of_order;
  std::stable_sort(keys.begin(), keys.end(),
                   [](const StampedPose& a, const StampedPose& b) { return a.time < b.time; });
  std::vector<StampedPose> merged;
  merged.reserve(keys.size());
  for (auto& k : keys) {
    if (!merged.empty() && merged.back().time == k.time) {
      const auto& p = merged.back();
      if (p.pose.q.coeffs() != k.pose.q.coeffs() || p.pose.t != k.pose.t)
        throw Error(source, k.line,
                    "timestamp " + std::to_string(k.time) + " repeats line " +
                        std::to_string(p.line) + " with a different pose");
      continue;
    }
    merged.push_back(k);
  }
  keys.swap(merged);
  return out_of_order;
}

std::optional<Rigid3d> InterpolateCameraToWorld(const std::vector<StampedPose>& keys, double time,
                                                Outside outside) {
  if (keys.empty()) return std::nullopt;
  if (time <= keys.front().time || time >= keys.back().time) {
    if (time == keys.front().time) return keys.front().pose;
    if (time == keys.back().time) return keys.back().pose;
    if (outside == Outside::kDrop) return std::nullopt;
    return time < keys.front().time ? keys.front().pose : keys.back().pose;
  }
  auto it = std::upper_bound(keys.begin(), keys.end(), time,
                             [](double t, const StampedPose& k) { return t < k.time; });
  const StampedPose& b = *it;
  const StampedPose& a = *(it - 1);
  if (a.time == time) return a.pose;
  double s = (time - a.time) / (b.time - a.time);
  Rigid3d r;
  r.q = Slerp(a.pose.q, b.pose.q, s);
  r.t = a.pose.t + s * (b.pose.t - a.pose.t);
  return r;
}

}  // namespace mvtm
