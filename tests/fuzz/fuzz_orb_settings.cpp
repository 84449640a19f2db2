// mvtm — libFuzzer harness: ORB-SLAM2 settings YAML (ReadOrbSettings, from a temporary .yaml file).
// Accepts only mvtm::Error; see fuzz_util.h.
#include "base/error.h"
#include "fuzz_util.h"
#include "io/trajectory.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  mvtm::fuzz::TempFile file(data, size, ".yaml");
  try {
    mvtm::ReadOrbSettings(file.path());
  } catch (const mvtm::Error&) {
  }
  try {
    mvtm::ReadOrbSettings(file.path(), 640, 480);
  } catch (const mvtm::Error&) {
  }
  return 0;
}
