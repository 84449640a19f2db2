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

// `pass`: image names starting with it ("" all); `start`: the start image's name ("" the first).
// Throws Error (no images) or UsageError (no such start image).
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

}  // namespace mvtm
