// mvtm — tracks.tsv: segtrack's vehicle tracks, one row per blob per frame.
//
// Format (segtrack(1), section "Output"; mvtm-workspace(5)): one header line
//   frame name track state x y w h cx cy area scx scy sw sh
// then one row per blob per frame, sorted by frame, then track; fields separated by one tab:
// the frame number (from 0), the frame's label file name, the track id (from 1), the state
// (detected, interpolated or rejected), the bounding box, centroid and pixel count of the
// blob's pixels, and the track's smoothed centroid and box size at that frame.
// Integers are written plainly; decimals with exactly three digits after the point ("%.3f"),
// whatever the locale. Reading a written file gives back every value that has at most three
// decimals exactly.
// The reader checks the header, the field count, every number and state, and the order, and
// reports "FILE:LINE: what". Fields the file does not hold (TrackRow::blob, draw_x, draw_y)
// read as 0. The path writer is atomic (a temporary file, then a rename).
// Thread safety: functions are reentrant.
#pragma once

#include <istream>
#include <ostream>
#include <string>
#include <vector>

#include "track/track_row.h"

namespace mvtm {

// One row of tracks.tsv: a tracker row and the label file name of its frame.
struct TracksTsvRow {
  std::string name;
  TrackRow row;
};

void WriteTracksTsv(std::ostream& out, const std::vector<TracksTsvRow>& rows);
void WriteTracksTsv(const std::string& path, const std::vector<TracksTsvRow>& rows);
// Throws Error("NAME:LINE: what"); `name` stands for the file in messages.
std::vector<TracksTsvRow> ReadTracksTsv(std::istream& in, const std::string& name);
std::vector<TracksTsvRow> ReadTracksTsv(const std::string& path);

}  // namespace mvtm
