// segtrack — semantic label images → cleaned per-frame vehicle masks and tracks (thesis §D.1),
// and the ranking of sequences by total vehicle area (thesis §5.2.1, Eq. 5.1).
#pragma once

#include <filesystem>
#include <string>
#include <vector>

#include "run/option_table.h"
#include "track/tracker.h"

namespace mvtm {

struct SegtrackOptions {
  std::vector<std::string> paths;  // LABELDIR WS; with rank: LABELDIR...
  std::string classes = "8";  // vehicle class ids, comma-separated (class-id or palette labels)
  std::string palette;        // palette image: the labels are RGB colours of these classes
  bool binary = false;        // the labels are masks: first channel non-zero = vehicle
  TrackOptions track;         // association, gap filling, smoothing, rejection, dilation
  bool rank = false;          // print the sequences ordered by total vehicle area instead
  bool force = false;         // rewrite the outputs even when they are up to date
  bool quiet = false;         // no progress bar, no summary

  void Check() const;  // throws UsageError naming the bad value
};

// The option table (run/option_table.h) bound to `o`: --help, the range checks, the provenance
// and the staleness key of the masks and tracks.tsv. PATHS is not in it (a table positional
// holds one value; main.cpp declares the list).
OptionTable DeclareOptions(SegtrackOptions& o);

struct SegtrackReport {
  TrackSummary summary;  // zero when nothing was tracked (everything up to date)
  std::filesystem::path masks_dir, tracks;
  size_t frames = 0;                // label images
  bool tracked = false;             // the frames were tracked (some output was stale)
  size_t written = 0, skipped = 0;  // outputs (masks and tracks.tsv) written / up to date
  std::string why;  // why existing outputs were remade ("61 redone: --dilate changed"), or ""
};

// Tracks LABELDIR's label images (*.png, in byte order of their names) and writes
// WS/masks/NAME.png and WS/tracks.tsv, each unless it is up to date, and the record
// WS/provenance/segtrack.json (run/ledger.h). Tracking couples the frames, so every label image
// (and the palette) is an input of every output. Throws Error / UsageError.
SegtrackReport RunSegtrack(const SegtrackOptions& options);

struct RankRow {
  std::string labeldir;
  size_t frames = 0;
  double area = 0;      // Eq. 5.1: vehicle pixels summed over all frames
  double fraction = 0;  // area / (frames * width * height)
};
// One row per LABELDIR, fewest vehicle pixels first (ties: LABELDIR in byte order).
std::vector<RankRow> RankSequences(const SegtrackOptions& options);

// The label images of a folder: regular files named *.png, sorted by name (byte order).
// Throws Error when `dir` is not a folder or holds none.
std::vector<std::filesystem::path> ListLabelImages(const std::filesystem::path& dir);

}  // namespace mvtm
