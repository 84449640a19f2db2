// boresight — a COLMAP model whose poses are of record (GPS/INS, SLAM, ground truth) turned by the
// one camera rotation that fits its feature tracks best (scene/boresight.h), the camera centres
// kept; the points moved with it. The rotation, the error it removes and the directions left as
// recorded go to OUTDIR/boresight.json.
#pragma once

#include <string>

#include "run/option_table.h"
#include "scene/boresight.h"

namespace mvtm {

struct BoresightToolOptions {
  std::string model;    // input COLMAP model folder (undistorted camera)
  std::string outdir;   // output model folder + boresight.json
  std::string exclude;  // file of image names (one per line) left out of the fit
  int min_track = 3;
  double min_angle = 1;  // degrees
  double max_error = 4;  // pixels
  double conditioning = 0.01;
  double min_gain = 0.05;
  bool binary = false;
  bool force = false;
  bool quiet = false;
  void Check() const;
};

OptionTable DeclareOptions(BoresightToolOptions& o);

struct BoresightReport {
  bool up_to_date = false;
  std::string why;
  BoresightFit fit;
  size_t excluded = 0;
};

// Writes OUTDIR's model and boresight.json unless they are up to date (run/ledger.h).
BoresightReport RunBoresight(const BoresightToolOptions& options);

}  // namespace mvtm
