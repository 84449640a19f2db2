// georef — a structure-from-motion model made upright and metric (scene/upright.h): up from the
// road under the cameras, metres from the camera's mounting height; optionally scored against a
// reference trajectory (ground truth, GPS-aligned poses) by the absolute trajectory error.
#pragma once

#include <string>

#include "run/option_table.h"

namespace mvtm {

struct GeorefOptions {
  std::string model;         // input COLMAP model folder
  std::string outdir;        // output model folder (cameras, images, points3D, georef.json)
  double camera_height = 0;  // metres above the road; 0: keep the model's unit
  std::string compare;       // reference trajectory (TUM or KITTI, camera-to-world)
  bool binary = false;       // write .bin instead of .txt
  bool force = false;
  bool quiet = false;

  void Check() const;
};

OptionTable DeclareOptions(GeorefOptions& o);

struct GeorefReport {
  bool up_to_date = false;
  std::string why;
  size_t cameras = 0, cameras_with_ground = 0, ground_points = 0;
  double camera_height = 0;  // model units, before scaling
  double height_spread = 0;  // model units (median absolute deviation)
  double scale = 1;          // applied
  double tilt_degrees = 0;   // between the road's up and the cameras' mean up
  // --compare: images matched, path length and ATE (reference units) after a similarity fit, and
  // the fit's scale (reference units per output unit: 1 for a metric output of a metric truth).
  size_t matched = 0;
  double path_length = 0, ate_rmse = 0, reference_scale = 0;
};

// Writes OUTDIR's model and georef.json unless they are up to date (run/ledger.h).
GeorefReport RunGeoref(const GeorefOptions& options);

}  // namespace mvtm
