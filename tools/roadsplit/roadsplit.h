// roadsplit — a long workspace split into a road of overlapping fragments (thesis Appendix D.3):
// ROAD/Graph.txt and one workspace per fragment under ROAD/Models/SEQ/FRAGMENT/
// (workspace/road.h).
//
// The path of record is the longest sequence of images (a sequence: the folder and the name's
// stem up to its last '_', SEQ_NNNN...; bare names without one form one) in name order, through
// its camera centres.
// Every image and mesh triangle gets the arc length of its nearest point on that path
// (index/path_index.h). The path is cut into fragments of equal length near --length; a
// fragment owns the images and triangles of its own stretch and holds copies of those within
// --overlap of it, so each fragment is a workspace every tool runs on alone, and the union of
// the owned triangles is the mesh, each triangle once. Where the path passes within
// --junction-radius of an earlier stretch of itself (a loop closure), the two fragments become
// neighbours (a junction) and hold each other's images there.
#pragma once

#include <string>

#include "run/option_table.h"

namespace mvtm {

struct RoadSplitOptions {
  std::string workspace;  // WS
  std::string road;       // ROAD (created)
  double length = 150;    // target fragment length, model units
  double overlap = 20;    // model units
  double junction_radius = 8;
  bool force = false;
  bool quiet = false;

  void Check() const;
};

OptionTable DeclareOptions(RoadSplitOptions& o);

struct RoadSplitReport {
  bool up_to_date = false;
  std::string why;  // why the road was (re)made ("" when new)
  size_t fragments = 0, junctions = 0, images = 0, triangles = 0;
  double path_length = 0, fragment_length = 0;
  size_t linked = 0, copied = 0;  // per-image files hard-linked or copied
};

// Writes ROAD (into a temporary folder beside it, renamed when complete) unless it is up to date
// (run/ledger.h: ROAD/provenance/roadsplit.json; the inputs are the model, the mesh,
// exposure.tsv and every image's files). Throws UsageError when ROAD is a folder that is not a
// road or the fragments would be too short for the overlap, Error for a workspace that cannot
// be split.
RoadSplitReport RunRoadSplit(const RoadSplitOptions& options);

}  // namespace mvtm
