// orb2colmap — SLAM or ground-truth poses → a COLMAP model of every frame (thesis §D.3.1).
#pragma once

#include <string>
#include <utility>
#include <vector>

#include "geometry/interpolate.h"
#include "io/trajectory.h"
#include "run/option_table.h"

namespace mvtm {

// --input-format: detect the trajectory format, or read it as TUM or KITTI.
enum class OrbInputFormat { kAuto, kTum, kKitti };
inline const std::vector<std::pair<OrbInputFormat, std::string>> kOrbInputFormats = {
    {OrbInputFormat::kAuto, "auto"},
    {OrbInputFormat::kTum, "tum"},
    {OrbInputFormat::kKitti, "kitti"}};
// --outside: frames outside the keyframe time span (geometry/interpolate.h).
inline const std::vector<std::pair<Outside, std::string>> kOrbOutside = {
    {Outside::kDrop, "drop"}, {Outside::kClamp, "clamp"}};

// TRAJECTORY '-': no poses (the camera and the images into the database, for SfM).
inline const std::string kNoTrajectory = "-";

struct Orb2ColmapOptions {
  std::string trajectory;  // TUM / ORB-SLAM2 / KITTI poses (camera-to-world)
  std::string outdir;      // the model is written here (cameras, images, points3D)
  OrbInputFormat input_format = OrbInputFormat::kAuto;
  std::string trajectory_times;      // KITTI: times.txt giving the timestamp of each pose line
  std::string frames;                // frame timestamps: KITTI times.txt, TUM rgb.txt, "time name"
  std::string images;                // folder whose files name the frames (sorted by name)
  std::string camera;                // "MODEL W H PARAMS..."
  std::string orb_settings;          // ORB-SLAM2 settings YAML
  std::string kitti_calib;           // KITTI calib.txt
  int kitti_cam = 0;                 // which Pn of calib.txt
  int kitti_poses_cam = -1;          // whose poses TRAJECTORY holds (-1: by its format)
  std::string size;                  // WxH when the intrinsics source has no image size
  bool binary = false;               // write .bin instead of .txt
  std::string database;              // create or fill a COLMAP database.db with pose priors
  Outside outside = Outside::kDrop;  // frames outside the keyframe time span
  bool force = false;                // rewrite an up-to-date model (and database)
  bool quiet = false;

  void Check() const;  // throws UsageError naming the bad value
};

// The option table (run/option_table.h) bound to `o`: --help, the range checks, the provenance
// and the staleness key of the model (and database).
OptionTable DeclareOptions(Orb2ColmapOptions& o);

struct Orb2ColmapReport {
  size_t keyframes = 0, frames = 0, written = 0, dropped = 0, clamped = 0, reordered = 0;
  // Each pose moved from camera `from` of --kitti-calib to camera `to` (--kitti-cam) by `offset`
  // (metres, in the camera's frame: x right, y down, z forward); from == to: not moved.
  int from_cam = 0, to_cam = 0;
  Eigen::Vector3d offset = Eigen::Vector3d::Zero();
  bool up_to_date = false;  // nothing done: the model (and database) are up to date
  std::string why;          // why existing outputs were rewritten ("3 redone: --outside changed")
};

// Writes the model into OUTDIR (and fills --database) unless every one of them is up to date by
// the record OUTDIR/provenance/orb2colmap.json (run/ledger.h): same options that change them,
// same inputs (the trajectory, --trajectory-times, --frames, --orb-settings, --kitti-calib, the
// image files of --images), and not changed since.
Orb2ColmapReport RunOrb2Colmap(const Orb2ColmapOptions& options);

}  // namespace mvtm
