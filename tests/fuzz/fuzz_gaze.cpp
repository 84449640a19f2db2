// mvtm — libFuzzer harness: gazemap's GAZE trace (ReadGazeTsv, gaze/gaze_tsv.h, stream version).
// Accepts only mvtm::Error; see fuzz_util.h.
#include <sstream>

#include "base/error.h"
#include "fuzz_util.h"
#include "gaze/gaze_tsv.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  std::istringstream in(mvtm::fuzz::AsString(data, size));
  try {
    mvtm::ReadGazeTsv(in, "gaze.tsv");
  } catch (const mvtm::Error&) {
  }
  return 0;
}
