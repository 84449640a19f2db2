// drive — steered trajectories for ptmrender: a controls log (steering-wheel angle, speed)
// through the kinematic bicycle model as exact arcs (drive/bicycle.h), or the recorded path with
// a smooth lane change (drive/lane_change.h), driven on the workspace's mesh (drive/ground.h).
// Writes the camera poses as a TUM or KITTI trajectory or a COLMAP text model, for
// `ptmrender --poses`. The model, the options and their limits: man drive(1).
//
// Scale: the car's lengths are metres; `scale` (model units per metre) maps them to the model.
// It is --scale S, or 1 with --metric or when the workspace records that it is metric
// (Workspace::MetricRecord: roadmesh --metric); otherwise the run is a UsageError that says so.
// Time: the controls' own times; with --lane-change, t = 0 at the start image and recorded image
// k (of the pass, from the start image) at k / frame_rate.
// Conventions: poses of record are COLMAP's; double precision throughout (UTM coordinates).
// Up to date: OUT's files (the trajectory file, or the model's cameras.txt, images.txt and
// points3D.txt) are remade unless the record beside them says they were made with these options
// from unchanged inputs (the sparse model, the mesh, CONTROLS, and the metric record when the
// scale comes from it). The record (run/ledger.h) is WS/provenance/drive.json when OUT is inside
// the workspace, else provenance/drive.json in the folder OUT's files are in.
// A road (ROAD/Graph.txt, roadsplit) in place of WS: the recorded drive is the road's recorded
// frames in order; the car drives on the own triangles of the fragment it is in and its graph
// neighbours (the fragment of its nearest recorded image), the next ones read ahead; a car that
// leaves the road or the graph is an error (workspace/road_locator.h).
#pragma once

#include <string>
#include <utility>
#include <vector>

#include "run/option_table.h"

namespace mvtm {

// --format: a TUM file, a COLMAP text model folder, a KITTI poses file.
enum class DriveFormat { kTum, kColmap, kKitti };
inline const std::vector<std::pair<DriveFormat, std::string>> kDriveFormats = {
    {DriveFormat::kTum, "tum"}, {DriveFormat::kColmap, "colmap"}, {DriveFormat::kKitti, "kitti"}};

struct DriveOptions {
  std::string workspace;
  std::string controls;        // CONTROLS: time steer speed log (empty with --lane-change)
  std::string out;             // OUT: a file (tum, kitti) or a folder (colmap)
  std::string lane_change;     // T0:DURATION:OFFSET (s, s, m): drive the recorded path instead
  double scale = 0;            // model units per metre, > 0; 0: not given
  bool metric = false;         // the model is in metres (--scale 1)
  double wheelbase = 2.7;      // metres, [0.5, 20]
  double steering_ratio = 15;  // steering-wheel angle per road-wheel angle, [1, 100]
  double max_steer = 35;       // largest road-wheel angle, degrees, (0, 89]
  double track = 1.6;          // metres between left and right wheels, [0.2, 5]
  std::string camera_offset;   // "X,Y,Z" metres forward, left, up of the ground under the rear
                               // axle centre; empty: 0,0,H (H: recorded height above the mesh)
  std::string start;           // image whose pose the drive starts at; empty: the first
  std::string pass;            // the recorded images: names starting with this; empty: all
  double frame_rate = 10;      // --lane-change: recorded images per second, (0, 1000]
  double rate = 10;            // output poses per second, (0, 1000]
  DriveFormat format = DriveFormat::kTum;
  bool force = false;  // rewrite OUT even when it is up to date
  bool quiet = false;

  // Throws UsageError naming the bad value and the allowed range.
  void Check() const;
};

// The option table (run/option_table.h) bound to `o`: --help, checks, provenance and the
// staleness key of OUT all come from it.
OptionTable DeclareOptions(DriveOptions& o);

struct DriveReport {
  bool up_to_date = false;
  std::string why;  // why OUT was remade ("1 redone: --rate changed"), "" when it was new
  size_t poses = 0;
  double duration = 0;                       // seconds
  double length = 0;                         // metres along the rear axle's path (steered), else 0
  double scale = 1;                          // model units per metre used
  std::string scale_source;                  // "--scale", "--metric", or the metric record's path
  std::vector<std::string> ignored_columns;  // CONTROLS columns not read
  size_t clamped = 0;        // control samples whose steering was clamped to --max-steer
  double camera_height = 0;  // metres: the camera offset's up part
  bool height_from_workspace = false;
  size_t height_cameras = 0;  // recorded cameras above the mesh (for the default height)
  double max_pitch_deg = 0, max_roll_deg = 0;  // largest |pitch|, |roll| of the car
  std::string output;                          // the file written (colmap: OUT/images.txt)
  size_t fragments = 0;  // a road: the fragments the car was in (entered), else 0
};

DriveReport RunDrive(const DriveOptions& options);

}  // namespace mvtm
