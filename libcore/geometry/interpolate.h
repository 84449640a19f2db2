// mvtm — pose interpolation in time.
//
// Keyframe trajectories (ORB-SLAM2 KeyFrameTrajectory.txt, every Nth ground-truth pose) are
// camera-to-world. Between two keyframes the rotation is SLERPed (shorter arc, see Slerp) and the
// camera centre is interpolated linearly, both with s = (t - t0) / (t1 - t0). A time exactly on a
// keyframe returns that keyframe unchanged (bit for bit).
#pragma once

#include <optional>
#include <string>
#include <vector>

#include "geometry/rigid.h"

namespace mvtm {

struct StampedPose {
  double time = 0;
  Rigid3d pose;   // camera-to-world unless the container says otherwise
  long line = 0;  // source line, for messages (0 when not from a file)
};

enum class Outside { kDrop, kClamp };

// Sorts keyframes by time (stable). Two keyframes with the same time are merged when their poses
// are identical and rejected otherwise (Error naming both lines of `source`).
// Returns the number of keyframes that were out of order (0 when the input was sorted).
size_t SortKeyframes(std::vector<StampedPose>& keys, const std::string& source);

// Pose at `time`, from keyframes sorted by strictly increasing time (as left by SortKeyframes).
// Outside [first, last]: std::nullopt for kDrop, the nearest end pose for kClamp.
std::optional<Rigid3d> InterpolateCameraToWorld(const std::vector<StampedPose>& keys, double time,
                                                Outside outside);

}  // namespace mvtm
