// mvtm — a driving controls log (drive's CONTROLS): steering-wheel angle and speed over time.
//
// Format: text, fields separated by tabs or blanks, '#' comments and blank lines skipped. The
// first line is a header naming the columns; it must name `time` (seconds), `steer` (steering-
// wheel angle in degrees, positive turns left) and `speed` (metres per second, negative:
// reversing), in any order. Other columns (e.g. `throttle brake` of a simulator log) are not read;
// their names are returned so the tool can say once that they were ignored. Every row has as
// many fields as the header. Times strictly increase; numbers are read in the classic "C" locale
// and must be finite.
//   time  steer  speed
//   0     0      10
//   4.0   37.5   10
// Sample i holds from its time until the next sample's (piecewise constant, drive/bicycle.h); the
// last sample ends the log.
// Errors are Error("FILE:LINE: what"): no header, a missing or repeated column, a wrong field
// count, a bad or non-finite number, a time not after the previous one, fewer than two samples.
// Thread safety: functions are reentrant.
#pragma once

#include <iosfwd>
#include <string>
#include <vector>

#include "drive/bicycle.h"

namespace mvtm {

struct ControlsLog {
  std::vector<ControlSample> samples;
  std::vector<std::string> ignored;  // header names of the columns not read, in file order
};

ControlsLog ReadControlsTsv(std::istream& in, const std::string& name);
ControlsLog ReadControlsTsv(const std::string& path);

}  // namespace mvtm
