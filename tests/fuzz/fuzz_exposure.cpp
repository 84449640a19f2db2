// mvtm — libFuzzer harness: exposure.tsv (ReadExposureTsv, stream version).
// Accepts only mvtm::Error; see fuzz_util.h.
#include <sstream>

#include "base/error.h"
#include "fuzz_util.h"
#include "io/exposure_tsv.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  std::istringstream in(mvtm::fuzz::AsString(data, size));
  try {
    mvtm::ReadExposureTsv(in, "exposure.tsv");
  } catch (const mvtm::Error&) {
  }
  return 0;
}
