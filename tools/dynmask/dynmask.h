// dynmask — vehicles, cyclists and pedestrians masked without labels: each photo checked against
// its neighbours of the same drive and its partners of the other drives of the road (a vehicle
// parked in one drive only), warped through the static reconstruction (libcore/dynamic), the
// evidence turned into blobs and tracked as segtrack tracks labels (libcore/track).
#pragma once

#include <cstddef>
#include <string>

#include "cli/work.h"
#include "dynamic/dynamic.h"
#include "run/option_table.h"
#include "track/tracker.h"

namespace mvtm {

enum class DepthSource { kAuto, kMesh, kStereo };

// Work items: the workspace's images sorted by name (--frames/--shard select the probability
// maps computed; the masks, which tracking couples, are made by a run without them).
struct DynmaskOptions : WorkOptions {
  std::string workspace;
  int max_width = 640;           // working resolution: images wider are scaled down to this
  int neighbours = 4;            // photos of the same drive each photo is checked against
  int partners = 2;              // photos of other drives each photo is also checked against
  int partners_ahead = 4;        // ... and photos of other drives farther along the road
  int ahead = 2;                 // photos of the same drive farther along the road
  double ahead_min_share = 0.1;  // ... none nearer than this share of the depth it stands for
  double min_baseline = 0.25;    // nearest neighbour allowed, in median camera spacings
  DepthSource depth = DepthSource::kAuto;  // auto: the mesh, else densify's maps
  std::string mesh;  // --mesh: the mesh to ray-cast ("": dynmask-mesh.ply, kept at the first run)
  bool no_flow = false;         // --no-flow: photometric evidence only
  bool no_colour = false;       // --no-colour: the luma's photometric residual only
  bool no_driven_grow = false;  // --no-driven-grow: densify's marked pixels only
  double grounded = 0.25;       // blobs must touch the ground within this × camera height; 0: off
  int passes = 2;  // 2: neighbours' pixels that their own first pass finds moving are left out
  double min_height = 0.5;       // blobs must rise this × the camera's height; 0: off
  double seen_tolerance = 0.05;  // pixels where densify's depth is the static one: static; 0 off
  double occludes = 0.2;         // blobs must hide something behind them (share); 0: off
  double occlusion_gap = 0.25;   // ... beyond their foot's depth by this (relative)
  double max_fill = 0.5;  // blobs with more of their pixels on corridor walls: cleared there; 1 off
  double complete = 3;    // blobs completed by GrabCut, growing at most this × their area; 0 off
  DrivenSpace driven;     // --driven (0 off), --driven-above/-below/-agree: where cars drove
  DynamicOptions evidence;  // --threshold, --flow/--no-flow, --quantile, ...
  MaskOptions mask;         // --probability, --open, --close, --min-area
  TrackOptions track;       // segtrack's tracking options (defaults: the constructor)
  std::string also;         // folder of masks OR-ed into the output (e.g. a video overlay)
  std::string labels;       // folder of label images: blobs confirmed or rejected by geometry
  std::string classes = "8,9,10";  // their classes (CamVid: car, pedestrian, cyclist)
  double confirm = 0.25;           // a label blob whose mean probability reaches this is masked
  double gap_support = 0.05;       // a gap filled by tracking needs this mean probability; 0: off

  // Tracking as segtrack's but for: max_jump 0 (a quarter width: probability blobs jump more
  // than label blobs); max_gap 3 (a blob of light at the image border and a vehicle entering
  // there frames later are not one vehicle to interpolate); min_life 2 (photos metres apart see
  // a vehicle passing the camera in two). min_ratio is segtrack's 0.5: at 0.4 two false blobs
  // four frames apart made a track and the three frames between were filled (mkroad's 150 m
  // winding road, seed 7: IoU 0.648 at 0.4, 0.705 at 0.5; the 80 m street's four seeds and
  // CamVid 0016E5 the same at both).
  DynmaskOptions() { track.max_jump = 0, track.max_gap = 3, track.min_life = 2; }
  void Check() const;
};

OptionTable DeclareOptions(DynmaskOptions& o);

struct DynmaskReport {
  size_t images = 0, written = 0, skipped = 0;  // probability maps
  size_t no_neighbours = 0;  // images no neighbour, partner or photo farther along saw a pixel of
  size_t with_partners = 0;  // images checked against another drive's photos too
  size_t with_ahead = 0;     // images checked against their drive's photos farther along too
  size_t with_veto = 0;      // images whose partners' evidence those photos could veto
  size_t with_behind = 0;    // ... of them at their drive's end: vetoed by the photos behind
  size_t floating = 0;       // blobs removed: not standing on the ground
  size_t lying = 0;          // blobs removed: flat in the road (wet patches, shadows)
  size_t surface = 0;        // blobs removed: on the static surface, hiding nothing
  size_t guessed = 0;        // blobs removed: mostly on a corridor wall (a guessed depth)
  size_t explained = 0;      // pixels cleared: the photo's own depth is the static depth there
  size_t completed = 0;      // blobs grown by GrabCut (--complete)
  size_t driven = 0;         // pixels raised: seen where a drive's car passed (--driven)
  bool masked = false;       // masks and tracks.tsv were (re)made
  size_t masks_written = 0;
  TrackSummary summary;
  double masked_share = 0;  // mean share of the image masked
  double ms_per_image = 0;  // evidence time per map written
  std::string depth_source;
  std::string why;
};

// Writes WS/dynamic/NAME.png for the selected images that are stale, then (without --frames or
// --shard) WS/masks/NAME.png and WS/tracks.tsv from every image's map. Throws Error/UsageError.
DynmaskReport RunDynmask(const DynmaskOptions& options);

}  // namespace mvtm
