#include "drive.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <functional>
#include <memory>
#include <nlohmann/json.hpp>

#include "base/atomic_file.h"
#include "base/error.h"
#include "base/stats.h"
#include "base/text.h"
#include "cli/work.h"
#include "drive/controls_tsv.h"
#include "drive/ground.h"
#include "drive/lane_change.h"
#include "io/colmap_model.h"
#include "io/mesh_io.h"
#include "io/trajectory.h"
#include "raycast/mesh_raycaster.h"
#include "workspace/workspace.h"

namespace mvtm {

namespace {

Eigen::Vector3d ParseOffset(const std::string& text) {
  const auto f = SplitChar(text, ',');
  if (f.size() != 3)
    throw UsageError("--camera-offset: expected X,Y,Z in metres (forward, left, up), got '" + text +
                     "'");
  Eigen::Vector3d v;
  for (int k = 0; k < 3; ++k) v[k] = ParseDoubleArg(f[k], "--camera-offset");
  if (!(v.z() > 0)) throw UsageError("--camera-offset: the height Z must be > 0 metres");
  return v;
}

// The recorded images of the pass, their poses (normalised) and the start image.
struct Recorded {
  Reconstruction rec;
  std::vector<const ImageRecord*> images;
  std::vector<Rigid3d> w2c;
  size_t start = 0;
};

Recorded LoadRecorded(const Workspace& ws, const DriveOptions& o) {
  Recorded r;
  r.rec = ReadColmapModel(ws.SparseDir().string());
  for (const ImageRecord* im : r.rec.ImagesByName())
    if (im->name.compare(0, o.pass.size(), o.pass) == 0) {
      r.images.push_back(im);
      r.w2c.emplace_back(NormalizedQuaternion(im->world_to_camera.q), im->world_to_camera.t);
    }
  if (r.images.empty())
    throw Error(ws.SparseDir().string(), 0,
                o.pass.empty() ? "the model has no images"
                               : "no image name starts with '" + o.pass + "' (--pass)");
  if (!o.start.empty()) {
    size_t i = 0;
    while (i < r.images.size() && r.images[i]->name != o.start) ++i;
    if (i == r.images.size())
      throw UsageError("--start: no image '" + o.start + "' in the workspace" +
                       (o.pass.empty() ? "" : " whose name starts with '" + o.pass + "'"));
    r.start = i;
  }
  return r;
}

// Model units per metre, and where that came from.
double ResolveScale(const DriveOptions& o, const Workspace& ws, const std::vector<double>& heights,
                    std::string& source) {
  if (o.scale > 0) {
    source = "--scale";
    return o.scale;
  }
  const fs::path record = ws.MetricRecord();
  if (o.metric || !record.empty()) {
    source = o.metric ? "--metric" : record.string();
    return 1.0;
  }
  std::string hint;
  if (!heights.empty()) {
    const double h = Median(heights);
    hint = "; its cameras are " + FormatDouble(std::round(h * 1e4) / 1e4) +
           " model units above the mesh, i.e. --scale " +
           FormatDouble(std::round(h / 1.65 * 1e4) / 1e4) + " for a camera 1.65 m high";
  }
  throw UsageError(ws.root().string() +
                   " is not known to be metric: give --scale S (model units per metre) or "
                   "--metric" +
                   hint);
}

// The car's path: time → rear axle pose, and the output times.
struct CarPath {
  std::function<PlanarPose(double)> at;
  std::vector<double> times;
};

CarPath SteeredCarPath(const ControlsLog& log, const DriveOptions& o, const CarGeometry& car,
                       const PlanarPose& start_foot, DriveReport& rep) {
  const BicycleParams b{o.wheelbase, o.steering_ratio, o.max_steer};
  auto path = std::make_shared<SteeredPath>(log.samples, b, RearAxleUnder(start_foot, car));
  rep.clamped = path->clamped();
  rep.length = path->length();
  CarPath c;
  c.times = SampleTimes(path->start_time(), path->end_time(), o.rate);
  c.at = [path](double t) { return path->At(t); };
  return c;
}

CarPath LaneChangeCarPath(const Recorded& r, const RoadFrame& frame, const DriveOptions& o,
                          const CarGeometry& car) {
  auto samples = std::make_shared<std::vector<PlanarSample>>();
  for (size_t i = r.start; i < r.w2c.size(); ++i)
    samples->push_back(
        {static_cast<double>(i - r.start) / o.frame_rate, PlanarCamera(frame, r.w2c[i])});
  if (samples->size() < 2)
    throw UsageError("--lane-change: the recorded path from the start image has one image");
  // Images of several drives in name order (no --pass) make a path that jumps between them or
  // turns back on itself.
  std::vector<Eigen::Vector3d> steps;
  std::vector<double> lengths;
  for (size_t i = r.start + 1; i < r.w2c.size(); ++i) {
    steps.push_back(r.w2c[i].Centre() - r.w2c[i - 1].Centre());
    lengths.push_back(steps.back().norm());
  }
  const double typical = Median(lengths);
  for (size_t k = 0; k < steps.size(); ++k) {
    // (Steps much shorter than usual, a car standing still in pose noise, never count as back.)
    const bool jump = lengths[k] > 5 * typical,
               back = k > 0 && std::min(lengths[k], lengths[k - 1]) > 0.2 * typical &&
                      steps[k].dot(steps[k - 1]) < 0;
    if (jump || back)
      throw UsageError("--lane-change: the recorded path " +
                       std::string(jump ? "jumps" : "turns back") + " from " +
                       r.images[r.start + k]->name + " to " + r.images[r.start + k + 1]->name +
                       ": choose one drive with --pass");
  }
  const LaneChange lc = LaneChange::Parse(o.lane_change);
  CarPath c;
  c.times = SampleTimes(0, samples->back().time, o.rate);
  c.at = [samples, lc, car](double t) {
    return RearAxleUnder(LaneChangePose(*samples, lc, t), car);
  };
  return c;
}

std::vector<StampedPose> Place(const MeshRaycaster& mesh, const RoadFrame& frame,
                               const CarGeometry& car, const CarPath& path, DriveReport& rep) {
  GroundPlacer placer(mesh, frame, car);
  std::vector<StampedPose> poses;
  for (double t : path.times) {
    const Placement p = placer.Place(path.at(t), t);
    rep.max_pitch_deg = std::max(rep.max_pitch_deg, std::abs(p.pitch) * 180 / M_PI);
    rep.max_roll_deg = std::max(rep.max_roll_deg, std::abs(p.roll) * 180 / M_PI);
    poses.push_back({t, p.camera_to_world, 0});
  }
  return poses;
}

// OUT as TUM, KITTI, or a COLMAP text model (the workspace's camera, images 000000.png, ...).
void WriteOutput(const DriveOptions& o, const Recorded& r, const std::vector<StampedPose>& poses) {
  if (o.format == "tum") return WriteTum(o.out, poses);
  if (o.format == "kitti") return WriteKittiPoses(o.out, poses);
  Reconstruction model;
  const Camera& cam = r.rec.cameras.at(r.images[r.start]->camera_id);
  model.cameras[cam.id] = cam;
  char name[32];
  for (size_t i = 0; i < poses.size(); ++i) {
    ImageRecord im;
    im.id = static_cast<uint32_t>(i + 1);
    im.camera_id = cam.id;
    std::snprintf(name, sizeof name, "%06zu.png", i);
    im.name = name;
    im.world_to_camera = poses[i].pose.Inverse();
    model.images[im.id] = im;
  }
  WriteColmapText(model, o.out);
}

std::string OutputFile(const DriveOptions& o) {
  return o.format == "colmap" ? (fs::path(o.out) / "images.txt").string() : o.out;
}

void WriteDriveProvenance(const Workspace& ws, const DriveOptions& o, const CarGeometry& car,
                          const DriveReport& rep, const std::vector<fs::path>& inputs) {
  nlohmann::json opts = {
      {"controls", o.controls},
      {"out", o.out},
      {"lane_change", o.lane_change},
      {"scale", rep.scale},
      {"scale_source", rep.scale_source},
      {"wheelbase", o.wheelbase},
      {"steering_ratio", o.steering_ratio},
      {"max_steer", o.max_steer},
      {"track", o.track},
      {"camera_offset", {car.camera_offset.x(), car.camera_offset.y(), car.camera_offset.z()}},
      {"start", o.start},
      {"pass", o.pass},
      {"frame_rate", o.frame_rate},
      {"rate", o.rate},
      {"format", o.format},
      {"poses", rep.poses}};
  ws.WriteProvenance("drive", opts, inputs);
}

}  // namespace

void DriveOptions::Check() const {
  if (lane_change.empty() && controls.empty())
    throw UsageError("give CONTROLS, or --lane-change T0:DURATION:OFFSET");
  if (!lane_change.empty() && !controls.empty())
    throw UsageError("--lane-change drives the recorded path: give WS OUT, no CONTROLS");
  if (out.empty()) throw UsageError("OUT is required");
  if (!lane_change.empty()) LaneChange::Parse(lane_change);
  if (scale != 0) CheckRange(scale, 0, 1e12, true, "--scale");
  if (scale != 0 && metric) throw UsageError("give --scale or --metric, not both");
  CheckRange(wheelbase, 0.5, 20, false, "--wheelbase (metres)");
  CheckRange(steering_ratio, 1, 100, false, "--steering-ratio");
  CheckRange(max_steer, 0, 89, true, "--max-steer (degrees)");
  CheckRange(track, 0.2, 5, false, "--track (metres)");
  if (!camera_offset.empty()) ParseOffset(camera_offset);
  CheckRange(frame_rate, 0, 1000, true, "--frame-rate (Hz)");
  CheckRange(rate, 0, 1000, true, "--rate (Hz)");
  CheckChoice(format, kDriveFormats, "--format");
}

DriveReport RunDrive(const DriveOptions& o) {
  o.Check();
  DriveReport rep;
  ControlsLog log;
  if (o.lane_change.empty()) log = ReadControlsTsv(o.controls);  // a bad log fails first, fast
  rep.ignored_columns = log.ignored;
  const Workspace ws(o.workspace);
  ws.Require("drive", {WsItem::kSparse, WsItem::kMesh});
  std::vector<fs::path> inputs = ws.SparseModelFiles();
  inputs.push_back(ws.MeshPath());
  if (!o.controls.empty()) inputs.emplace_back(o.controls);
  rep.output = OutputFile(o);
  if (!o.force && IsUpToDate(rep.output, inputs)) {
    rep.up_to_date = true;
    return rep;
  }
  const Recorded r = LoadRecorded(ws, o);
  const MeshRaycaster mesh(ReadMesh(ws.MeshPath().string()));
  const Eigen::Vector3d up = RecordedUp(r.w2c);
  const std::vector<double> heights = CameraHeights(mesh, r.w2c, up);
  rep.height_cameras = heights.size();
  rep.scale = ResolveScale(o, ws, heights, rep.scale_source);
  CarGeometry car{o.wheelbase, o.track, Eigen::Vector3d::Zero()};
  if (!o.camera_offset.empty()) {
    car.camera_offset = ParseOffset(o.camera_offset);
  } else {
    if (heights.empty())
      throw Error(ws.MeshPath().string(), 0,
                  "no recorded camera is above the mesh: give --camera-offset X,Y,Z");
    car.camera_offset = Eigen::Vector3d(0, 0, Median(heights) / rep.scale);
    rep.height_from_workspace = true;
  }
  rep.camera_height = car.camera_offset.z();
  const RoadFrame frame = FrameAtCamera(r.w2c[r.start], up, rep.scale);
  const CarPath path = o.lane_change.empty()
                           ? SteeredCarPath(log, o, car, PlanarCamera(frame, r.w2c[r.start]), rep)
                           : LaneChangeCarPath(r, frame, o, car);
  const std::vector<StampedPose> poses = Place(mesh, frame, car, path, rep);
  rep.poses = poses.size();
  rep.duration = path.times.back() - path.times.front();
  WriteOutput(o, r, poses);
  WriteDriveProvenance(ws, o, car, rep, inputs);
  return rep;
}

}  // namespace mvtm
