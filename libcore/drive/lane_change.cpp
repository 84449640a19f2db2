#include "drive/lane_change.h"

#include <algorithm>
#include <cmath>

#include "base/error.h"
#include "base/text.h"

namespace mvtm {

LaneChange LaneChange::Parse(const std::string& text) {
  const auto f = SplitChar(text, ':');
  if (f.size() != 3)
    throw FieldError("lane_change",
                     "expected T0:DURATION:OFFSET (seconds, seconds, metres), got '" + text + "'");
  LaneChange lc;
  try {
    lc.start = ParseDoubleArg(f[0], "T0");
    lc.duration = ParseDoubleArg(f[1], "DURATION");
    lc.offset = ParseDoubleArg(f[2], "OFFSET");
  } catch (const UsageError& e) {
    throw FieldError("lane_change", e.what());
  }
  if (!(lc.duration > 0)) throw FieldError("lane_change", "DURATION must be > 0 seconds");
  return lc;
}

LaneChange::Value LaneChange::At(double t) const {
  Value v;
  const double s = (t - start) / duration;
  if (s <= 0) return v;
  if (s >= 1) {
    v.d = offset;
    return v;
  }
  const double s2 = s * s, s3 = s2 * s;
  v.d = offset * s3 * (10 + s * (-15 + 6 * s));
  v.velocity = offset / duration * 30 * s2 * (1 + s * (-2 + s));  // 30σ²(1 − σ)²
  v.acceleration = offset / (duration * duration) * 60 * s * (1 + s * (-3 + 2 * s));
  return v;
}

PlanarPose LaneChangePose(const std::vector<PlanarSample>& path, const LaneChange& lc, double t) {
  if (path.empty()) throw Error("the recorded path is empty");
  size_t i = 0;
  double w = 0;  // weight of sample i + 1
  if (path.size() > 1 && t > path.front().time) {
    i = std::min<size_t>(static_cast<size_t>(std::upper_bound(path.begin(), path.end(), t,
                                                              [](double x, const PlanarSample& s) {
                                                                return x < s.time;
                                                              }) -
                                             path.begin()) -
                             1,
                         path.size() - 2);
    w = std::clamp((t - path[i].time) / (path[i + 1].time - path[i].time), 0.0, 1.0);
  }
  const PlanarPose& a = path[i].pose;
  const PlanarPose& b = path[std::min(i + 1, path.size() - 1)].pose;
  const double dt = path.size() > 1 ? path[i + 1].time - path[i].time : 1;
  const double turn = std::remainder(b.heading - a.heading, 2 * M_PI);
  PlanarPose p;
  p.x = a.x + w * (b.x - a.x);
  p.y = a.y + w * (b.y - a.y);
  const double heading = a.heading + w * turn;
  const double v = std::hypot(b.x - a.x, b.y - a.y) / dt;
  const LaneChange::Value d = lc.At(t);
  if (v == 0 && d.velocity != 0)
    throw Error("the lane change moves sideways at t = " + FormatDouble(t) +
                " s while the recorded path stands still");
  p.x -= d.d * std::sin(heading);
  p.y += d.d * std::cos(heading);
  p.heading = std::remainder(heading + std::atan2(d.velocity, v), 2 * M_PI);
  return p;
}

}  // namespace mvtm
