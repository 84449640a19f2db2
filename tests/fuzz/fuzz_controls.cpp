// mvtm — libFuzzer harness: drive's CONTROLS log (ReadControlsTsv, drive/controls_tsv.h, stream
// version). Accepts only mvtm::Error; see fuzz_util.h.
#include <sstream>

#include "base/error.h"
#include "drive/controls_tsv.h"
#include "fuzz_util.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  std::istringstream in(mvtm::fuzz::AsString(data, size));
  try {
    mvtm::ReadControlsTsv(in, "controls.tsv");
  } catch (const mvtm::Error&) {
  }
  return 0;
}
