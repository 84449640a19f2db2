// mvtm — an eye tracker's gaze trace (gazemap's GAZE): where on the screen the eye looked, when.
//
// Format: text, fields separated by tabs or blanks, '#' comments and blank lines skipped. The
// first line is a header naming the columns; it must name `time` (seconds, on the clock of the
// FRAMES' display times), `x` and `y` (screen pixels: x right, y down, (0, 0) the top-left corner
// of the screen, so the centre of the top-left pixel is (0.5, 0.5)), and may name `valid` (1: the
// tracker has the eye, 0: it has not). Other columns (e.g. `pupil`) are not read; their names are
// returned so the tool can say once that they were ignored. Every row has as many fields as the
// header. Numbers are read in the classic "C" locale.
//   time    x      y      valid
//   0.000   960.5  540.2  1
//   0.004   nan    nan    0
// A sample is *invalid* when its `valid` is 0 or its x or y is not finite ("nan", "inf": what
// trackers write for a lost eye, a blink); invalid samples are kept (the I-VT filter fills short
// gaps) and counted. Times must be finite and strictly increase.
// Errors are Error("FILE:LINE: what"): no header, a missing or repeated column, a wrong field
// count, a bad number, a non-finite time, a `valid` other than 0 or 1, a time not after the
// previous one (unsorted or repeated), fewer than two samples.
// Thread safety: functions are reentrant.
#pragma once

#include <iosfwd>
#include <string>
#include <vector>

namespace mvtm {

struct GazeSample {
  double time = 0;      // seconds
  double x = 0, y = 0;  // screen pixels (see above); meaningful only when valid
  bool valid = true;
  long line = 0;  // source line, for messages
};

struct GazeTrace {
  std::vector<GazeSample> samples;
  std::vector<std::string> ignored;  // header names of the columns not read, in file order
  size_t invalid_flagged = 0;        // samples with valid = 0
  size_t invalid_nonfinite = 0;      // samples with valid = 1 (or no column) but x or y not finite
};

GazeTrace ReadGazeTsv(std::istream& in, const std::string& name);
GazeTrace ReadGazeTsv(const std::string& path);

}  // namespace mvtm
