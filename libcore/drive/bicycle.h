// mvtm — the kinematic bicycle (Ackermann) model of a car at its rear axle (thesis App. B.2),
// integrated as exact circular arcs.
//
// Conventions:
//  * The planar state is the rear axle centre (x, y) in metres and the heading ψ in radians,
//    counter-clockwise from +x, in a right-handed road plane (x forward at the start, y left, z
//    up; drive/ground.h maps it onto the mesh). ψ is kept in [−π, π].
//  * x' = v cos ψ, y' = v sin ψ, ψ' = v tan δ / L: δ the road-wheel angle (positive: left), L the
//    wheelbase, v the speed (negative: reversing). With δ and v constant the rear axle runs on a
//    circle of radius L / tan δ, so one step is the exact arc, not an Euler step:
//      θ = κ·s (κ = tan δ / L, s = v·Δt),
//      forward = s·sin(θ)/θ,  left = s·(1 − cos θ)/θ = s·sin(θ/2)·sinc(θ/2),
//    in the frame of the heading at the start of the step. Both ratios are evaluated in forms that
//    are exact at θ = 0 and accurate next to it, so δ → 0 is a straight line with no 0/0.
//  * Controls are piecewise constant: sample i holds from its time to the next sample's. The
//    state is integrated from knot to knot (the sample times) and any time in between is one arc
//    from the knot before it, so the pose at a knot — the end pose in particular — does not
//    depend on the times at which poses are asked for (the output rate), bit for bit.
// Thread safety: pure functions and immutable objects.
#pragma once

#include <cstddef>
#include <vector>

namespace mvtm {

struct PlanarPose {
  double x = 0, y = 0;  // rear axle centre, metres
  double heading = 0;   // ψ, radians, in [−π, π]
};

// sin(x)/x, 1 at x = 0.
double Sinc(double x);
// (1 − cos x)/x as sin(x/2)·sinc(x/2): 0 at x = 0, no cancellation near it.
double Versinc(double x);

// Drives `distance` metres (negative: backwards) along the arc of signed curvature `curvature`
// (1/m, positive: turning left) from `p`. Exact for curvature 0 (a straight line).
PlanarPose AdvanceArc(const PlanarPose& p, double distance, double curvature);

struct BicycleParams {
  double wheelbase = 2.7;      // L, metres (a passenger car)
  double steering_ratio = 15;  // steering-wheel angle / road-wheel angle
  double max_steer_deg = 35;   // largest road-wheel angle, degrees; larger ones are clamped
};

// Road-wheel angle δ (radians) of a steering-wheel angle in degrees, clamped to ±max_steer_deg;
// `clamped` (optional) is set when it was.
double RoadWheelAngle(double steering_wheel_deg, const BicycleParams& params,
                      bool* clamped = nullptr);

// One control sample: from `time` on, the steering wheel at `steer_deg` and the speed `speed`.
struct ControlSample {
  double time = 0;       // seconds
  double steer_deg = 0;  // steering-wheel angle, degrees, positive turns left
  double speed = 0;      // metres per second
  long line = 0;         // source line, for messages (0: not from a file)
};

// The path of the rear axle under piecewise-constant controls (strictly increasing times, at
// least one sample), starting at `start` at the first sample's time.
class SteeredPath {
 public:
  SteeredPath(const std::vector<ControlSample>& controls, const BicycleParams& params,
              const PlanarPose& start);
  // Appends a sample after the last (a live drive: simulate samples its controls as it goes);
  // the path is then the one the constructor makes from all samples, bit for bit. Throws Error
  // when its time is not after the last sample's.
  void Append(const ControlSample& c);
  // The pose at time t, clamped to [start_time(), end_time()].
  PlanarPose At(double t) const;
  // The pose at time t ≥ start_time() with the last sample's controls held past end_time() (a
  // live drive between its samples); At(t) up to end_time().
  PlanarPose Continued(double t) const;
  double speed() const { return speed_.back(); }  // the last sample's speed
  double start_time() const { return times_.front(); }
  double end_time() const { return times_.back(); }
  size_t clamped() const { return clamped_; }  // samples whose steering angle was clamped
  double length() const { return length_; }    // |distance| driven, metres

 private:
  BicycleParams params_;
  std::vector<double> times_, speed_, curvature_;
  std::vector<PlanarPose> knots_;  // the pose at each sample time
  size_t clamped_ = 0;
  double length_ = 0;
};

// Output times: t0, t0 + 1/rate, t0 + 2/rate, … up to t1, each computed as t0 + k/rate (no
// accumulation); t1 itself always ends the list (a grid point within 1e-9 s of it is replaced by
// it), so the last output pose is the end pose.
std::vector<double> SampleTimes(double t0, double t1, double rate);

}  // namespace mvtm
