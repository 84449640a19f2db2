// mvtm — libFuzzer harness: KITTI calib.txt (ReadKittiCalib, from a temporary file), cameras P0 and
// P2. Accepts only mvtm::Error; see fuzz_util.h.
#include "base/error.h"
#include "fuzz_util.h"
#include "io/trajectory.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  mvtm::fuzz::TempFile file(data, size, ".txt");
  for (int cam : {0, 2}) {
    try {
      mvtm::ReadKittiCalib(file.path(), cam, 1241, 376);
    } catch (const mvtm::Error&) {
    }
  }
  return 0;
}
