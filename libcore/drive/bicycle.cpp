#include "drive/bicycle.h"

#include <algorithm>
#include <cmath>

#include "base/error.h"

namespace mvtm {

double Sinc(double x) {
  // Below 1e-4 the series 1 − x²/6 + x⁴/120 is exact to double precision (next term x⁶/5040).
  if (std::abs(x) < 1e-4) {
    const double x2 = x * x;
    return 1 - x2 / 6 * (1 - x2 / 20);
  }
  return std::sin(x) / x;
}

double Versinc(double x) { return std::sin(0.5 * x) * Sinc(0.5 * x); }

namespace {

double WrapAngle(double a) {
  if (a > M_PI || a < -M_PI) a = std::remainder(a, 2 * M_PI);
  return a;
}

}  // namespace

PlanarPose AdvanceArc(const PlanarPose& p, double distance, double curvature) {
  const double theta = curvature * distance;
  const double forward = distance * Sinc(theta);
  const double left = distance * Versinc(theta);
  const double c = std::cos(p.heading), s = std::sin(p.heading);
  PlanarPose q;
  q.x = p.x + (forward * c - left * s);
  q.y = p.y + (forward * s + left * c);
  q.heading = WrapAngle(p.heading + theta);
  return q;
}

double RoadWheelAngle(double steering_wheel_deg, const BicycleParams& b, bool* clamped) {
  double deg = steering_wheel_deg / b.steering_ratio;
  const bool clamp = std::abs(deg) > b.max_steer_deg;
  if (clamp) deg = std::copysign(b.max_steer_deg, deg);
  if (clamped) *clamped = clamp;
  return deg * M_PI / 180.0;
}

SteeredPath::SteeredPath(const std::vector<ControlSample>& controls, const BicycleParams& b,
                         const PlanarPose& start)
    : params_(b) {
  if (controls.empty()) throw Error("no control samples");
  knots_.push_back(start);
  for (const ControlSample& c : controls) Append(c);
}

void SteeredPath::Append(const ControlSample& c) {
  if (!times_.empty()) {
    if (!(c.time > times_.back())) throw Error("control sample times must increase");
    const double s = speed_.back() * (c.time - times_.back());
    length_ += std::abs(s);
    knots_.push_back(AdvanceArc(knots_.back(), s, curvature_.back()));
  }
  bool clamped = false;
  const double delta = RoadWheelAngle(c.steer_deg, params_, &clamped);
  clamped_ += clamped;
  times_.push_back(c.time);
  speed_.push_back(c.speed);
  curvature_.push_back(std::tan(delta) / params_.wheelbase);
}

PlanarPose SteeredPath::At(double t) const {
  if (!(t > times_.front())) return knots_.front();
  if (t >= times_.back()) return knots_.back();
  const size_t i =
      static_cast<size_t>(std::upper_bound(times_.begin(), times_.end(), t) - times_.begin()) - 1;
  if (t == times_[i]) return knots_[i];
  return AdvanceArc(knots_[i], speed_[i] * (t - times_[i]), curvature_[i]);
}

PlanarPose SteeredPath::Continued(double t) const {
  if (!(t > times_.back())) return At(t);
  return AdvanceArc(knots_.back(), speed_.back() * (t - times_.back()), curvature_.back());
}

std::vector<double> SampleTimes(double t0, double t1, double rate) {
  std::vector<double> out;
  const double n = std::floor((t1 - t0) * rate + 1e-9);
  for (double k = 0; k <= n; ++k) out.push_back(t0 + k / rate);
  // The end time itself ends the list (a grid point within 1e-9 s of it is replaced by it).
  if (std::abs(t1 - out.back()) <= 1e-9)
    out.back() = t1;
  else
    out.push_back(t1);
  return out;
}

}  // namespace mvtm
