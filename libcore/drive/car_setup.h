// mvtm — a car set on a workspace's road: the recorded images of one drive, the model's unit in
// metres and the car's camera height. Shared by drive (offline) and simulate (live), so both put
// the same car at the same start.
//
// Scale: the car's lengths are metres; `scale` (model units per metre) maps them to the model.
// It is --scale S, or 1 with --metric or when the workspace records that it is metric
// (Workspace::MetricRecord: roadmesh --metric); otherwise a UsageError that says so, with the
// scale the recorded cameras' height suggests.
// Conventions: poses of record are COLMAP's (world to camera), quaternions normalised.
// Thread safety: pure functions.
#pragma once

#include <string>
#include <vector>

#include "drive/ground.h"
#include "io/colmap_model.h"
#include "workspace/workspace.h"

namespace mvtm {

// The recorded images of the pass, their poses (normalised) and the start image.
struct RecordedDrive {
  Reconstruction rec;
  std::vector<const ImageRecord*> images;  // name order, names starting with the pass
  std::vector<Rigid3d> w2c;
  size_t start = 0;
};

// The recorded drive among `images` (any order): names starting with `pass` ("" all), in name
// order, from the image named `start` ("" the first). Throws Error naming `file` (no images) or
// UsageError ("--start: no image 'NAME' HELD ...": HELD says where it was looked for).
RecordedDrive SelectRecordedDrive(std::vector<const ImageRecord*> images, const std::string& pass,
                                  const std::string& start, const std::string& file,
                                  const std::string& held);

// The workspace's recorded drive (SelectRecordedDrive over its model). Throws as it does.
RecordedDrive LoadRecordedDrive(const Workspace& ws, const std::string& pass,
                                const std::string& start);

// Model units per metre and where that came from ("--scale", "--metric", the metric record).
// `tool` names the caller for the metric record (its own record does not count).
double ResolveScale(double scale, bool metric, const Workspace& ws,
                    const std::vector<double>& heights, const std::string& tool,
                    std::string& source);

// "X,Y,Z" metres forward, left, up; UsageError (naming `option`) when malformed or Z <= 0.
Eigen::Vector3d ParseCameraOffset(const std::string& text, const std::string& option);

// The car: the camera offset given ("" for the recorded cameras' median height above the mesh,
// `heights` in model units, over `scale`). Sets `from_workspace` when the height is the
// recorded one. Throws Error when no recorded camera is above the mesh and none is given.
CarGeometry MakeCar(double wheelbase, double track, const std::string& camera_offset,
                    const Workspace& ws, const std::vector<double>& heights, double scale,
                    bool* from_workspace);

// What sets a car on the road (drive's and simulate's options of the same names).
struct CarOptions {
  double scale = 0;  // model units per metre; 0: not given
  bool metric = false;
  double wheelbase = 2.7, track = 1.6;
  std::string camera_offset;  // "" for the recorded height
  std::string pass, start;
};

// The car set on the road: the recorded drive, the road frame at the start image, the car and
// the scale, with where the scale and height came from.
struct CarOnRoad {
  RecordedDrive rec;
  RoadFrame frame;
  CarGeometry car;
  double scale = 1;
  std::string scale_source;
  size_t height_cameras = 0;  // recorded cameras above the mesh
  bool height_from_workspace = false;
};

// LoadRecordedDrive, the recorded up axis and camera heights over `mesh`, ResolveScale (for
// `tool`), MakeCar and FrameAtCamera at the start image, in that order.
CarOnRoad SetUpCar(const Workspace& ws, const MeshRaycaster& mesh, const CarOptions& o,
                   const std::string& tool);

}  // namespace mvtm
