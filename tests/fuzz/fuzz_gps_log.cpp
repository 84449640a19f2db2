// mvtm — libFuzzer harness: GPS logs (geo/gps_log.h): the input as a GPX or NMEA log (detected by
// content), and as an ISO 8601 time.
// Accepts only mvtm::Error; see fuzz_util.h.
#include <sstream>

#include "base/error.h"
#include "fuzz_util.h"
#include "geo/gps_log.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  const std::string text = mvtm::fuzz::AsString(data, size);
  try {
    std::istringstream in(text);
    const mvtm::GpsLog log = mvtm::ReadGpsLog(in, "log");
    for (size_t i = 1; i < log.fixes.size(); ++i)
      if (!(log.fixes[i].time > log.fixes[i - 1].time)) __builtin_trap();  // sorted, merged
  } catch (const mvtm::Error&) {
  }
  double t;
  mvtm::ParseIsoTime(text, t);
  return 0;
}
