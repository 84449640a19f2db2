// mvtm — libFuzzer harness: NeRF transforms.json (ReadNerfTransforms, from a temporary file).
// Accepts only mvtm::Error; see fuzz_util.h.
#include "base/error.h"
#include "fuzz_util.h"
#include "io/trajectory.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  mvtm::fuzz::TempFile file(data, size, ".json");
  try {
    mvtm::ReadNerfTransforms(file.path());
  } catch (const mvtm::Error&) {
  }
  return 0;
}
