// mvtm — libFuzzer harness: tracks.tsv (ReadTracksTsv, stream version).
// Accepts only mvtm::Error; see fuzz_util.h.
#include <sstream>

#include "base/error.h"
#include "fuzz_util.h"
#include "io/tracks.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  std::istringstream in(mvtm::fuzz::AsString(data, size));
  try {
    mvtm::ReadTracksTsv(in, "tracks.tsv");
  } catch (const mvtm::Error&) {
  }
  return 0;
}
