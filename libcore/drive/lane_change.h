// mvtm — a lane change as a smooth lateral offset in time (drive --lane-change).
//
// The offset d(t) = D·q(σ), σ = (t − T0)/T clamped to [0, 1], with the quintic minimum-jerk
// profile q(σ) = 10σ³ − 15σ⁴ + 6σ⁵ (Flash & Hogan 1985): q(0) = 0, q(1) = 1, and q', q'' vanish
// at both ends, so d, the lateral velocity d' and the lateral acceleration d'' are continuous
// everywhere (the jerk is not). Peak lateral velocity 1.875·D/T at the middle, peak lateral
// acceleration (10/√3)·D/T² ≈ 5.774·D/T² at σ = (3 ∓ √3)/6.
// Units: seconds and metres; D positive moves to the left, negative to the right (as ptmrender's
// --lateral).
// Thread safety: value type.
#pragma once

#include <string>
#include <vector>

#include "drive/bicycle.h"

namespace mvtm {

struct LaneChange {
  double start = 0;     // T0, seconds from the start of the path
  double duration = 1;  // T, seconds, > 0
  double offset = 0;    // D, metres, left positive

  // Parses "T0:DURATION:OFFSET" (finite numbers, DURATION > 0); throws UsageError naming
  // --lane-change.
  static LaneChange Parse(const std::string& text);

  struct Value {
    double d = 0, velocity = 0, acceleration = 0;  // d, d', d''
  };
  Value At(double t) const;
};

// A recorded path in the road plane: where a point of the car (drive uses the camera's foot
// point) was at a time, and its heading. Times strictly increase.
struct PlanarSample {
  double time = 0;
  PlanarPose pose;
};

// The recorded path moved sideways by a lane change, at time t (clamped to the path's span):
// between two samples the position is linear and the heading turns along the shorter arc (as
// SLERP does for a level camera); the point moves d(t) to the left of that heading, and the
// heading turns by atan2(d'(t), v), v the recorded speed between the two samples, so the car
// points along the path it drives. Throws Error when the lane change moves sideways while the
// recorded path stands still (v = 0, d' ≠ 0).
PlanarPose LaneChangePose(const std::vector<PlanarSample>& path, const LaneChange& lane_change,
                          double t);

}  // namespace mvtm
