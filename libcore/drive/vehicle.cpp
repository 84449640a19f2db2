#include "drive/vehicle.h"

#include <algorithm>
#include <cmath>
#include <limits>

#include "base/error.h"

namespace mvtm {

double NextSpeed(double v, const Pedals& p, double dt, const LongitudinalParams& lp) {
  const double throttle = std::clamp(p.throttle, 0.0, 1.0);
  const double brake = std::clamp(p.brake, 0.0, 1.0);
  const double push = (p.reverse ? -1.0 : 1.0) * throttle * lp.max_accel;
  // Resistances and the brake act against the motion; at rest they hold the car (up to the push).
  const double resist = brake * lp.max_brake + (v != 0 ? lp.rolling + lp.drag * v * v : 0.0);
  double next;
  if (v > 0 || (v == 0 && push > 0)) {
    next = v + (push - resist) * dt;
    if (next < 0 && !(push < 0)) next = 0;
  } else if (v < 0 || push < 0) {
    next = v + (push + resist) * dt;
    if (next > 0 && !(push > 0)) next = 0;
  } else {
    next = 0;
  }
  return std::clamp(next, -lp.max_reverse, lp.max_speed);
}

RecordedPath::RecordedPath(std::vector<Eigen::Vector2d> feet) : feet_(std::move(feet)) {
  cumulative_.push_back(0);
  for (size_t i = 1; i < feet_.size(); ++i)
    cumulative_.push_back(cumulative_.back() + (feet_[i] - feet_[i - 1]).norm());
  if (feet_.size() < 2 || !(cumulative_.back() > 0))
    throw Error("the recorded drive has fewer than two distinct camera positions");
}

PathPoint RecordedPath::Project(const Eigen::Vector2d& p) const {
  PathPoint best;
  best.length = cumulative_.back();
  double best_d2 = std::numeric_limits<double>::infinity();
  for (size_t i = 0; i + 1 < feet_.size(); ++i) {
    const Eigen::Vector2d a = feet_[i], d = feet_[i + 1] - feet_[i];
    const double len2 = d.squaredNorm();
    if (len2 == 0) continue;
    const double u = std::clamp((p - a).dot(d) / len2, 0.0, 1.0);
    const Eigen::Vector2d q = a + u * d;
    const double d2 = (p - q).squaredNorm();
    if (d2 < best_d2) {
      best_d2 = d2;
      best.along = cumulative_[i] + u * std::sqrt(len2);
      const double cross = d.x() * (p - a).y() - d.y() * (p - a).x();  // > 0: p on the left
      best.offset = std::copysign(std::sqrt(d2), cross);
    }
  }
  return best;
}

size_t RecordedPath::Nearest(const Eigen::Vector2d& p) const {
  size_t best = 0;
  for (size_t i = 1; i < feet_.size(); ++i)
    if ((feet_[i] - p).squaredNorm() < (feet_[best] - p).squaredNorm()) best = i;
  return best;
}

void DrivingMeasures::Add(double dt, double v, double offset) {
  const double speed = std::abs(v);
  s_.duration += dt;
  s_.distance += speed * dt;
  sum_v_ += speed * dt;
  sum_v2_ += speed * speed * dt;
  sum_o_ += offset * dt;
  sum_o2_ += offset * offset * dt;
  s_.max_offset = std::max(s_.max_offset, std::abs(offset));
  if (s_.speed_limit > 0 && speed > s_.speed_limit) {
    sum_over2_ += (speed - s_.speed_limit) * (speed - s_.speed_limit) * dt;
    s_.time_over += dt;
  }
}

DrivingSummary DrivingMeasures::Summary() const {
  DrivingSummary s = s_;
  if (s.duration <= 0) return s;
  s.mean_speed = sum_v_ / s.duration;
  s.sd_speed = std::sqrt(std::max(0.0, sum_v2_ / s.duration - s.mean_speed * s.mean_speed));
  s.mean_offset = sum_o_ / s.duration;
  s.sdlp = std::sqrt(std::max(0.0, sum_o2_ / s.duration - s.mean_offset * s.mean_offset));
  s.rms_over_limit = std::sqrt(sum_over2_ / s.duration);
  return s;
}

}  // namespace mvtm
