// mvtm — the live car: pedals to speed (longitudinal dynamics), where the car is along the
// recorded drive (lane offset, progress), and the driving measures a study reads.
//
// Longitudinal model (per fixed simulation step dt, semi-implicit Euler on the speed only; the
// path itself stays drive's exact arcs, drive/bicycle.h, with the speed held over each step):
//   a = throttle · max_accel − sign(v) · (brake · max_brake + rolling + drag · v²)
//   v' = v + a · dt, never crossing zero through brake or resistance (a stopped car stays
//   stopped unless throttle pushes it), then clamped to [−max_reverse, max_speed].
// With `reverse` the throttle pushes backwards. Pedal values are clamped to [0, 1].
// Defaults are a mid-size car: 3 m/s² full throttle, 8 m/s² full brake, drag 0.00035 /m
// (½ρ·Cd·A/m = ½·1.2·0.3·2.2 / 1500 kg), rolling 0.15 m/s², 50 m/s cap, 3 m/s reversing.
//
// Recorded path: the planar polyline of the recorded cameras' foot points (drive/ground.h's road
// frame). Project() gives the arc length along it of the nearest point and the signed lateral
// offset (metres, left positive): the lane position of the thesis's measures.
//
// Driving measures (thesis §3.2.4), time-weighted over simulation steps: duration, distance,
// mean and standard deviation of speed, RMS of the speed's excess over a limit and the time over
// it, mean and standard deviation of the lateral offset (SDLP) and its largest magnitude.
// Thread safety: plain values; DrivingMeasures is not thread-safe.
#pragma once

#include <Eigen/Core>
#include <vector>

namespace mvtm {

struct Pedals {
  double steer_deg = 0;  // steering-wheel angle, degrees, positive turns left
  double throttle = 0;   // [0, 1]
  double brake = 0;      // [0, 1]
  bool reverse = false;  // the throttle pushes backwards
};

struct LongitudinalParams {
  double max_accel = 3.0;    // m/s² at full throttle
  double max_brake = 8.0;    // m/s² at full brake
  double drag = 0.00035;     // 1/m: deceleration per v²
  double rolling = 0.15;     // m/s² while moving
  double max_speed = 50.0;   // m/s
  double max_reverse = 3.0;  // m/s
};

// The speed after one step of dt seconds from speed v (m/s).
double NextSpeed(double v, const Pedals& pedals, double dt, const LongitudinalParams& params);

struct PathPoint {
  double along = 0;   // metres from the first recorded foot point along the polyline
  double offset = 0;  // metres to the left (+) or right (−) of it
  double length = 0;  // the whole polyline's length, metres
};

class RecordedPath {
 public:
  // `feet`: the recorded cameras' planar foot points in order (at least two distinct).
  explicit RecordedPath(std::vector<Eigen::Vector2d> feet);
  PathPoint Project(const Eigen::Vector2d& p) const;
  // The index of the recorded point nearest to `p` (where a reset puts the car back).
  size_t Nearest(const Eigen::Vector2d& p) const;
  double length() const { return cumulative_.back(); }

 private:
  std::vector<Eigen::Vector2d> feet_;
  std::vector<double> cumulative_;
};

struct DrivingSummary {
  double duration = 0, distance = 0;                 // s, m
  double mean_speed = 0, sd_speed = 0;               // m/s
  double speed_limit = 0;                            // m/s, 0: none given
  double rms_over_limit = 0, time_over = 0;          // m/s, s
  double mean_offset = 0, sdlp = 0, max_offset = 0;  // m
  size_t resets = 0;
};

class DrivingMeasures {
 public:
  explicit DrivingMeasures(double speed_limit) { s_.speed_limit = speed_limit; }
  // One simulation step of dt seconds at speed v (m/s, signed) and lateral offset (m).
  void Add(double dt, double v, double offset);
  void Reset() { ++s_.resets; }
  DrivingSummary Summary() const;

 private:
  DrivingSummary s_;
  double sum_v_ = 0, sum_v2_ = 0, sum_over2_ = 0, sum_o_ = 0, sum_o2_ = 0;
};

}  // namespace mvtm
