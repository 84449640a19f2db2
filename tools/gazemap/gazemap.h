// gazemap — eye tracking onto the road and back (thesis App. A.1, B.1, Ch. 6): an eye tracker's
// gaze on the screen showing ptmrender's frames → I-VT fixations (gaze/ivt.h) → the 3-D point on
// the workspace's mesh under each fixation, in the frame on screen at the fixation's middle
// (gaze/mapping.h: exact ray cast, refined in double) → every source photograph that sees the
// point unoccluded, with the pixel in it → dwell time per area of interest (gaze/aoi.h) and
// pictures (gaze/pictures.h). The formats, the model and the options: man gazemap(1).
//
// FRAMES is the trajectory given to ptmrender --poses (TUM, KITTI or COLMAP images.txt; frame i
// is the i-th pose, rendered as 000000.png, ... or the COLMAP image's name). Its display times:
// TUM's timestamps, or frame i at i / --frame-rate (required for KITTI and COLMAP files). The
// render camera is the workspace's first camera (as ptmrender's), shown full screen.
// Outputs (OUT/, all written atomically): fixations.tsv, sources.tsv, aoi.tsv,
// fixations/NAME.png (each source photo with its fixations), heatmap.png (top down).
// Up to date: each output is remade unless the record says it was made with these options from
// unchanged inputs (the sparse model, the mesh, FRAMES, GAZE, the boxes, the depth maps with
// --visibility depth, the label images without boxes; a picture also its photo); the pictures
// checked are those of the photos sources.tsv names, and those of them a new mapping draws on no
// more are removed (with pictures on). The record (run/ledger.h) is OUT/provenance/gazemap.json,
// or WS/provenance/gazemap.json when OUT is inside the workspace.
// A road (ROAD/Graph.txt, workspace/road.h) in place of a workspace: FRAMES walks the graph as
// ptmrender --poses does (workspace/road_locator.h); each fixation is mapped on the own triangles
// and own photos of the fragment its frame's camera is in and of its neighbours (read ahead on a
// second thread, the others dropped); the heat map paints every fragment, one at a time.
// Conventions: poses of record are COLMAP's; double precision throughout; times in seconds in the
// files, the I-VT options in milliseconds (as Tobii states them).
#pragma once

#include <string>
#include <utility>
#include <vector>

#include "gaze/aoi.h"
#include "run/option_table.h"

namespace mvtm {

// --visibility: a photo's baked depth map decides (a ray where it has none), or always a ray.
enum class GazeVisibility { kDepth, kRay };
inline const std::vector<std::pair<GazeVisibility, std::string>> kGazeVisibility = {
    {GazeVisibility::kDepth, "depth"}, {GazeVisibility::kRay, "ray"}};

struct GazemapOptions {
  std::string workspace, frames, gaze, out;
  double frame_rate = 0;        // frames per second: frame i shown at i / HZ (0: FRAMES' times)
  std::string screen;           // WxH screen pixels (empty: the render camera's size)
  std::string screen_mm;        // WxH physical screen size, millimetres
  double distance = 0;          // eye to screen, millimetres (with screen_mm)
  double px_per_degree = 0;     // instead of screen_mm and distance
  double max_gap = 75;          // ms, gap fill-in up to this (0: off), [0, 1000]
  int noise_median = 0;         // moving-median window, samples: 0 off, or odd in [3, 99]
  double velocity_window = 20;  // ms, (0, 1000]
  double threshold = 30;        // degrees per second, (0, 10000]
  double merge_time = 75;       // ms (0: no merging), [0, 1000]
  double merge_angle = 0.5;     // degrees, [0, 180]
  double min_duration = 60;     // ms (0: keep all), [0, 10000]
  GazeVisibility visibility = GazeVisibility::kDepth;
  double depth_tolerance = 0.01;  // relative, [0, 1]
  std::string aoi_boxes;          // AOIs from 3-D boxes (file); else the label images
  int heatmap_size = 1024;        // pixels of the heat map's larger side, [16, 16384]
  double heatmap_sigma = 0;       // model units (0: 1 % of the map)
  bool no_pictures = false;       // write no PNGs
  bool force = false;             // rewrite the outputs even when they are up to date
  bool quiet = false;

  // Throws UsageError naming the bad value and the allowed range.
  void Check() const;
};

// The option table (run/option_table.h) bound to `o`: --help, checks, provenance and the
// staleness key of the outputs all come from it.
OptionTable DeclareOptions(GazemapOptions& o);

struct GazemapReport {
  bool up_to_date = false;  // every output was up to date: nothing was computed
  std::string why;          // why outputs were remade ("5 redone: --threshold changed"), or ""
  std::vector<std::string> ignored_columns;  // GAZE columns not read
  size_t samples = 0, invalid_flagged = 0, invalid_nonfinite = 0;
  size_t gaps_filled = 0, samples_filled = 0;
  size_t fixations = 0, merged = 0, discarded = 0;
  size_t on_mesh = 0;      // fixations whose ray hit the mesh
  size_t with_source = 0;  // of those, seen by at least one photo
  size_t source_rows = 0;  // rows of sources.tsv
  size_t pictures = 0;     // PNGs written (up-to-date ones not counted)
  std::string aoi_from;    // "boxes FILE", "labels", or "none"
  std::vector<DwellRow> aoi;
};

GazemapReport RunGazemap(const GazemapOptions& options);

// Prints what main prints: the notes and the summary (unless quiet) on stderr, the dwell table on
// stdout (when up to date, the one in OUT/aoi.tsv).
void PrintGazemapReport(const GazemapOptions& options, const GazemapReport& report);

// The dwell table as written to aoi.tsv and printed (header "aoi fixations dwell share").
std::string FormatDwellTable(const std::vector<DwellRow>& rows);

}  // namespace mvtm
