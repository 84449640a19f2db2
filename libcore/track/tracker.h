// mvtm — vehicle tracking over a sequence of vehicle masks (thesis §D.1).
//
// The algorithm (stated precisely in segtrack(1), section "Tracking"):
//  1. Blobs: the 8-connected components of each frame's vehicle mask (track/blobs.h).
//  2. Association, frame by frame, greedy nearest: every live track predicts its centroid at
//     frame t by constant velocity from its last two detections (its last centroid when it has
//     one); all (track, blob) pairs with |prediction - blob centroid| <= max_jump are taken in
//     increasing distance (ties: lower track id, then lower blob index), each track and blob at
//     most once. Unmatched blobs start new tracks (ids 1, 2, ... in order of creation). A track
//     that has gone max_missed consecutive frames without a blob ends.
//  3. Smoothing: at each detection, centroid (cx, cy) and box size (w, h) are replaced by a
//     Gaussian-weighted local linear fit over the track's detections (sigma in frames, window
//     +-3 sigma), which leaves motion at constant speed unchanged, also at the ends of a track.
//  4. Gaps of at most max_gap frames between two detections are filled: centroid and size are
//     interpolated linearly between the smoothed values, and the last detected blob's pixels
//     are scaled (nearest neighbour) by the size ratio and moved so their centroid lands there.
//  5. Rejection, per stretch: a track is cut at its gaps longer than max_gap (never filled: a
//     sighting ends there); a stretch whose span (first to last detection, in frames) is shorter
//     than min_life, or whose detected/span ratio is below min_ratio, is a false positive. A
//     track is kept when one of its stretches is.
//
// Memory: every detection's pixels are kept until Finish() (the rejection needs a whole track).
// Thread safety: a Tracker is used from one thread; a finished TrackResult is read-only.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "track/blobs.h"
#include "track/track_row.h"

namespace mvtm {

struct TrackOptions {
  double max_jump = 50;    // pixels: largest distance between a track's prediction and its blob
  int max_missed = 50;     // frames: a track ends after this many consecutive frames without a blob
  int max_gap = 10;        // frames: longest run of missed frames that is filled by interpolation
  double smooth = 1.0;     // frames: Gaussian sigma for centroid and size (0: no smoothing)
  int min_life = 3;        // frames: stretches (step 5) spanning fewer frames are rejected
  double min_ratio = 0.5;  // stretches with detected/span below this are rejected
  int dilate = 0;          // pixels: radius of the disk the output masks are dilated by

  void Check() const;  // throws UsageError naming the bad value and the allowed range
};

class OptionTable;

// Declares the tracking options every masking tool shares, in this order, bound to `o`:
// --max-missed, --max-gap, --smooth, --min-life, --min-ratio, --dilate (segtrack, dynmask).
// --max-jump is each tool's own (its default and its meaning of 0 differ).
void DeclareTrackOptions(OptionTable& table, TrackOptions& o);

struct TrackSummary {
  int frames = 0, tracks = 0, kept = 0, rejected = 0;
  size_t detected = 0, interpolated = 0, rejected_blobs = 0, unfilled_gaps = 0;
  size_t unsupported_gaps = 0;  // interpolated rows RejectUnsupportedGaps turned to rejected
};

struct TrackResult {
  int width = 0, height = 0;
  std::vector<TrackRow> rows;  // sorted by frame, then track id
  std::vector<Blob> blobs;     // pixels referenced by rows
  TrackSummary summary;

  // Rows of frame f: [begin, end) indices into rows.
  std::pair<size_t, size_t> FrameRows(int frame) const;
  // Whether frame f has a row of state interpolated (a gap fill).
  bool HasInterpolated(int frame) const;
  // The output mask of `frame`: width*height bytes, 255 under the detected and interpolated blobs
  // of kept tracks, 0 elsewhere; then dilated by a disk of radius `dilate` (0: not dilated).
  void RenderMask(int frame, int dilate, std::vector<uint8_t>& out) const;

 private:
  friend class Tracker;
  std::vector<size_t> frame_begin_;  // frames+1 offsets into rows
};

// Gap filling checked against evidence the tracker never saw (dynmask's probability maps): in
// frame `frame` of `res`, each interpolated row whose pixels outside that frame's detected rows
// have a mean `evidence` (width×height values, row-major) below `min_mean` becomes rejected, so
// RenderMask leaves it out. A row with no such pixel (all under detected blobs or off the image)
// stays. The two ends of a gap need not be one vehicle: a track that lost its blob may take
// another one (two vehicles merged, a patch of light) a few frames on, and the interpolation
// between then paints what lies between them. Returns how many rows were rejected;
// summary.interpolated and summary.unsupported_gaps follow.
size_t RejectUnsupportedGaps(TrackResult& res, int frame, const float* evidence, double min_mean);

class Tracker {
 public:
  Tracker(int width, int height, const TrackOptions& options);

  // The next frame's vehicle mask (width*height bytes, non-zero = vehicle).
  void AddFrame(const uint8_t* vehicle);
  // The next frame given as blobs (as found by BlobFinder, or made by hand in tests).
  void AddBlobs(std::vector<Blob> blobs);
  int frames() const { return frames_; }

  // Smoothing, gap filling and rejection over everything added; the tracker is left empty.
  TrackResult Finish();

 private:
  struct Det {
    int frame;
    size_t blob;  // index into blobs_
  };
  struct Track {
    int id;
    std::vector<Det> dets;
  };
  // A track's smoothed centroid and box size at each of its detections.
  struct Smoothed {
    std::vector<double> cx, cy, w, h;
  };
  // The steps of Finish(), one track at a time, then the frame index of the sorted rows.
  Smoothed Smooth(const Track& tr, const std::vector<Blob>& blobs) const;
  // Per detection of `tr`: whether the stretch it belongs to is rejected (step 5).
  std::vector<uint8_t> Rejected(const Track& tr) const;
  void AddDetectedRows(const Track& tr, const Smoothed& s, const std::vector<uint8_t>& rejected,
                       TrackResult& res) const;
  void FillGaps(const Track& tr, const Smoothed& s, const std::vector<uint8_t>& rejected,
                TrackResult& res) const;
  void IndexFrames(TrackResult& res) const;
  int width_, height_;
  TrackOptions o_;
  int frames_ = 0;
  BlobFinder finder_;
  std::vector<Blob> blobs_;
  std::vector<Track> tracks_;
  std::vector<size_t> live_;  // indices into tracks_ of tracks that have not ended
};

}  // namespace mvtm
