// orb2colmap — SLAM or ground-truth poses → a COLMAP model of every frame (thesis §D.3.1).
#pragma once

#include <string>
#include <vector>

#include "geometry/interpolate.h"
#include "io/trajectory.h"

namespace mvtm {

// Choices of --input-format and --outside.
inline const std::vector<std::string> kOrbInputFormats = {"auto", "tum", "kitti"};
inline const std::vector<std::string> kOrbOutside = {"drop", "clamp"};

struct Orb2ColmapOptions {
  std::string trajectory;             // TUM / ORB-SLAM2 / KITTI poses (camera-to-world)
  std::string outdir;                 // the model is written here (cameras, images, points3D)
  std::string input_format = "auto";  // one of kOrbInputFormats
  std::string trajectory_times;       // KITTI: times.txt giving the timestamp of each pose line
  std::string frames;                 // frame timestamps: KITTI times.txt, TUM rgb.txt, "time name"
  std::string images;                 // folder whose files name the frames (sorted by name)
  std::string camera;                 // "MODEL W H PARAMS..."
  std::string orb_settings;           // ORB-SLAM2 settings YAML
  std::string kitti_calib;            // KITTI calib.txt
  int kitti_cam = 0;                  // which Pn of calib.txt
  std::string size;                   // WxH when the intrinsics source has no image size
  bool binary = false;                // write .bin instead of .txt
  std::string database;               // create or fill a COLMAP database.db with pose priors
  std::string outside = "drop";       // one of kOrbOutside: frames outside the keyframe time span
  bool force = false;                 // rewrite an up-to-date model
  bool quiet = false;

  void Check() const;  // throws UsageError naming the bad value
};

struct Orb2ColmapReport {
  size_t keyframes = 0, frames = 0, written = 0, dropped = 0, clamped = 0, reordered = 0;
  bool up_to_date = false;  // nothing done: the model is newer than every input
};

Orb2ColmapReport RunOrb2Colmap(const Orb2ColmapOptions& options);

}  // namespace mvtm
