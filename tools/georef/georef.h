// georef — a structure-from-motion model made upright and metric (scene/upright.h): up from the
// road under the cameras, metres from the camera's mounting height; optionally scored against a
// reference trajectory (ground truth, GPS-aligned poses) by the absolute trajectory error. With a
// GPS log (geo/gps_align.h) the model is placed in UTM: x east, y north, z up in metres about a
// recorded origin, the scale from GPS fused with the camera height's when both are given.
#pragma once

#include <string>

#include "run/option_table.h"

namespace mvtm {

struct GeorefOptions {
  std::string model;           // input COLMAP model folder
  std::string outdir;          // output model folder (cameras, images, points3D, georef.json)
  double camera_height = 0;    // metres above the road; 0: keep the model's unit
  std::string compare;         // reference trajectory (TUM or KITTI, camera-to-world)
  std::string gps;             // GPX or NMEA log
  std::string times;           // frame times: frames.tsv, "NAME TIME" lines, or KITTI times.txt
  double gps_offset = 0;       // seconds, geo/gps_align.h
  double gps_search = 0;       // seconds either side of gps_offset searched
  double gps_max_gap = 10;     // seconds
  double height_sigma = 0.02;  // relative standard error of the camera-height scale
  bool binary = false;         // write .bin instead of .txt
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
  // --gps: frames with a time, within the log, inliers, residual RMS (m), GPS-only scale and its
  // standard error (metres per model unit), the zone.
  bool gps = false;
  size_t gps_frames = 0, gps_matched = 0, gps_pairs = 0, gps_inliers = 0;
  size_t gps_bad_checksums = 0;  // NMEA sentences skipped
  double gps_rms = 0, scale_gps = 0, scale_gps_sigma = 0;
  std::string utm_zone, scale_source;
  double gps_offset = 0;  // the offset used
  // --compare: images matched, path length and ATE (reference units) after a similarity fit, and
  // the fit's scale (reference units per output unit: 1 for a metric output of a metric truth).
  size_t matched = 0;
  double path_length = 0, ate_rmse = 0, reference_scale = 0;
};

// Writes OUTDIR's model and georef.json unless they are up to date (run/ledger.h).
GeorefReport RunGeoref(const GeorefOptions& options);

}  // namespace mvtm
