// densify — a depth map with a confidence per workspace image by multi-view plane-sweep stereo
// on the CPU (libcore/stereo), for fusion into a dense mesh where COLMAP has no CUDA.
#pragma once

#include <string>

#include "cli/work.h"
#include "run/option_table.h"
#include "stereo/neighbours.h"
#include "stereo/plane_sweep.h"

namespace mvtm {

// Work items: the workspace's images sorted by name (--frames/--shard select among them).
struct DensifyOptions : WorkOptions {
  std::string workspace;
  double scale = 0;        // depth map size relative to the image (0 < F <= 1); 0: map_focal
  double map_focal = 360;  // with scale 0: the maps' focal length, pixels (at most the image's)
  int planes = 48;         // planes per sweep direction (2..512)
  bool no_ground = false, no_facade = false, no_fronto = false;  // sweep directions left out
  NeighbourOptions neighbours;  // --neighbours, --min-baseline, --max-angle, --min-coverage
  PlaneSweepOptions sweep;      // --window, --best-k, --min-score, --min-texture

  void Check() const;
};

// The option table (run/option_table.h) bound to `o`: --help, checks, provenance and the
// staleness key of the maps all come from it.
OptionTable DeclareOptions(DensifyOptions& o);

struct DensifyReport {
  size_t selected = 0, written = 0, skipped = 0, no_neighbours = 0;
  double valid_share = 0;   // mean share of pixels with a depth, over the maps written
  double ms_per_image = 0;  // sweep time per written map
  std::string why;          // why maps were remade ("4 redone: --planes changed"), "" when none was
};

DensifyReport RunDensify(const DensifyOptions& options);

}  // namespace mvtm
