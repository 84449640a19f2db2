// mvtm — libFuzzer harness: partners.tsv (ReadPartners, stream version).
// Accepts only mvtm::Error; see fuzz_util.h.
#include <sstream>

#include "base/error.h"
#include "fuzz_util.h"
#include "io/partners.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  std::istringstream in(mvtm::fuzz::AsString(data, size));
  try {
    mvtm::ReadPartners(in, "partners.tsv");
  } catch (const mvtm::Error&) {
  }
  return 0;
}
