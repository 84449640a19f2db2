// mvtm — one row of the tracker's output: one blob of one track in one frame.
//
// The data of a row of tracks.tsv (io/tracks.h reads and writes the file; segtrack(1) defines
// its columns) plus where the row's pixels are in the tracker's result. Header-only plain data,
// so that readers of tracks.tsv need not link the tracker.
// Units: pixels of the label images; frames counted from 0, track ids from 1.
// Thread safety: plain values.
#pragma once

#include <cstddef>

namespace mvtm {

enum class RowState { kDetected, kInterpolated, kRejected };
inline constexpr const char* kRowStateNames[] = {"detected", "interpolated", "rejected"};
// "detected", "interpolated", "rejected".
inline const char* RowStateName(RowState s) {
  const int i = static_cast<int>(s);
  return i >= 0 && i < 3 ? kRowStateNames[i] : "?";
}

// One blob of one track in one frame: a row of tracks.tsv.
struct TrackRow {
  int frame = 0;  // 0-based frame index
  int track = 0;  // track id, 1-based
  RowState state = RowState::kDetected;
  // The pixels drawn (detected, rejected: the blob as found; interpolated, and a gap fill that
  // RejectUnsupportedGaps rejected: the moved blob, clipped to the image): bounding box,
  // centroid, pixel count. An interpolated blob that falls entirely outside the image has area
  // 0 and an empty box at its unclipped position.
  int x = 0, y = 0, w = 0, h = 0;
  double cx = 0, cy = 0;
  int area = 0;
  // The track's smoothed centroid and box size at this frame.
  double scx = 0, scy = 0, sw = 0, sh = 0;
  // The pixels: `result.blobs[blob]` drawn with its box at (draw_x, draw_y).
  size_t blob = 0;
  int draw_x = 0, draw_y = 0;
};

}  // namespace mvtm
