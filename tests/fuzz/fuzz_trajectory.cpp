// mvtm — libFuzzer harness: trajectories and timestamps (io/trajectory.h stream readers): the same
// input goes to ReadTrajectory (format detection, then TUM, KITTI or COLMAP images.txt), ReadTum,
// ReadKittiPoses and ReadTimestamps.
// Accepts only mvtm::Error; see fuzz_util.h.
#include <sstream>

#include "base/error.h"
#include "fuzz_util.h"
#include "io/trajectory.h"

namespace {

template <class F>
void Try(const std::string& text, F read) {
  try {
    std::istringstream in(text);
    read(in);
  } catch (const mvtm::Error&) {
  }
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  const std::string text = mvtm::fuzz::AsString(data, size);
  Try(text, [](std::istream& in) { mvtm::ReadTrajectory(in, "traj.txt"); });
  Try(text, [](std::istream& in) {
    mvtm::ReadTrajectory(in, "images.txt", mvtm::TrajectoryFormat::kColmap);
  });
  Try(text, [](std::istream& in) { mvtm::ReadTum(in, "tum.txt"); });
  Try(text, [](std::istream& in) { mvtm::ReadKittiPoses(in, "poses.txt"); });
  Try(text, [](std::istream& in) { mvtm::ReadTimestamps(in, "times.txt"); });
  return 0;
}
