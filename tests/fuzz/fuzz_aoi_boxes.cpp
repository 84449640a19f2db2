// mvtm — libFuzzer harness: gazemap's --aoi-boxes file (ReadAoiBoxes, gaze/aoi.h, from a
// temporary file). Accepts only mvtm::Error; see fuzz_util.h.
#include "base/error.h"
#include "fuzz_util.h"
#include "gaze/aoi.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  mvtm::fuzz::TempFile file(data, size, ".txt");
  try {
    mvtm::ReadAoiBoxes(file.path());
  } catch (const mvtm::Error&) {
  }
  return 0;
}
