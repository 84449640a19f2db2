// mvtm — libFuzzer harness: pickview's QUERIES reader (tools/pickview/queries.h), from standard
// input
// ("-"), as `pickview WS -` reads it.
// Accepts only mvtm::Error; see fuzz_util.h.
#include <sstream>

#include "base/error.h"
#include "fuzz_util.h"
#include "queries.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  std::istringstream in(mvtm::fuzz::AsString(data, size));
  try {
    mvtm::ReadPickViewQueries("-", in);
  } catch (const mvtm::Error&) {
  }
  return 0;
}
