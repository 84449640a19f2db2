#include "drive.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <functional>
#include <map>
#include <memory>
#include <nlohmann/json.hpp>
#include <optional>
#include <set>

#include "base/atomic_file.h"
#include "base/error.h"
#include "base/stats.h"
#include "base/text.h"
#include "cli/work.h"
#include "drive/car_setup.h"
#include "drive/controls_tsv.h"
#include "drive/ground.h"
#include "drive/lane_change.h"
#include "drive/road_car.h"
#include "io/colmap_model.h"
#include "io/mesh_io.h"
#include "io/trajectory.h"
#include "raycast/mesh_raycaster.h"
#include "run/ledger.h"
#include "workspace/road.h"
#include "workspace/road_locator.h"
#include "workspace/road_meshes.h"
#include "workspace/workspace.h"

namespace mvtm {

namespace {

using Recorded = RecordedDrive;

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

// `follow` (a road): called after each placement with the camera's centre and time; returns the
// ground the next placements are on.
using FollowGround = std::function<const MeshRaycaster*(const Eigen::Vector3d&, double)>;

std::vector<StampedPose> Place(const MeshRaycaster& mesh, const RoadFrame& frame,
                               const CarGeometry& car, const CarPath& path, DriveReport& rep,
                               const FollowGround& follow = nullptr) {
  GroundPlacer placer(mesh, frame, car);
  std::vector<StampedPose> poses;
  for (double t : path.times) {
    const Placement p = placer.Place(path.at(t), t);
    if (follow) placer.UseMesh(*follow(p.camera_to_world.t, t));
    rep.max_pitch_deg = std::max(rep.max_pitch_deg, std::abs(p.pitch) * 180 / M_PI);
    rep.max_roll_deg = std::max(rep.max_roll_deg, std::abs(p.roll) * 180 / M_PI);
    poses.push_back({t, p.camera_to_world, 0});
  }
  return poses;
}

// OUT as TUM, KITTI, or a COLMAP text model (the workspace's camera, images 000000.png, ...).
void WriteOutput(const DriveOptions& o, const Recorded& r, const std::vector<StampedPose>& poses) {
  if (o.format == DriveFormat::kTum) return WriteTum(o.out, poses);
  if (o.format == DriveFormat::kKitti) return WriteKittiPoses(o.out, poses);
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

// The files OUT is: the trajectory file, or the COLMAP model's three.
std::vector<fs::path> OutputFiles(const DriveOptions& o) {
  if (o.format != DriveFormat::kColmap) return {o.out};
  const fs::path d(o.out);
  return {d / "cameras.txt", d / "images.txt", d / "points3D.txt"};
}

// Where drive's record goes: the workspace (or road) when OUT is inside it
// (WS/provenance/drive.json), else the folder OUT's files are in (OUT itself for a COLMAP model).
fs::path RecordRoot(const DriveOptions& o, const fs::path& root) {
  fs::path dir = o.format == DriveFormat::kColmap ? fs::path(o.out) : fs::path(o.out).parent_path();
  if (dir.empty()) dir = ".";
  const fs::path rel = fs::weakly_canonical(dir).lexically_relative(fs::weakly_canonical(root));
  const bool inside = !rel.empty() && rel.begin()->string() != "..";
  return inside ? root : dir;
}

// Every file OUT depends on: the sparse model, the mesh, CONTROLS, and the metric record when
// the scale comes from it.
std::vector<fs::path> DriveInputs(const DriveOptions& o, const Workspace& ws) {
  std::vector<fs::path> inputs = ws.SparseModelFiles();
  inputs.push_back(ws.MeshPath());
  if (!o.controls.empty()) inputs.emplace_back(o.controls);
  if (o.scale == 0 && !o.metric) {
    const fs::path record = ws.MetricRecord("drive");
    if (!record.empty()) inputs.push_back(record);
  }
  return inputs;
}

// Drives the car set on its road (on `ground`, which `follow` replaces as the car moves when
// given) and writes OUT.
void DriveCar(const DriveOptions& o, const CarOnRoad& set, const MeshRaycaster& ground,
              const ControlsLog& log, DriveReport& rep, const FollowGround& follow = nullptr) {
  const Recorded& r = set.rec;
  const CarGeometry& car = set.car;
  const RoadFrame& frame = set.frame;
  rep.height_cameras = set.height_cameras;
  rep.scale = set.scale;
  rep.scale_source = set.scale_source;
  rep.height_from_workspace = set.height_from_workspace;
  rep.camera_height = car.camera_offset.z();
  const CarPath path = o.lane_change.empty()
                           ? SteeredCarPath(log, o, car, PlanarCamera(frame, r.w2c[r.start]), rep)
                           : LaneChangeCarPath(r, frame, o, car);
  const std::vector<StampedPose> poses = Place(ground, frame, car, path, rep, follow);
  rep.poses = poses.size();
  rep.duration = path.times.back() - path.times.front();
  WriteOutput(o, r, poses);
}

CarOptions CarOptionsOf(const DriveOptions& o) {
  return {o.scale, o.metric, o.wheelbase, o.track, o.camera_offset, o.pass, o.start};
}

// Drives the car on a workspace's mesh and writes OUT.
void MakeDrive(const DriveOptions& o, const Workspace& ws, const ControlsLog& log,
               DriveReport& rep) {
  const MeshRaycaster mesh(ReadMesh(ws.MeshPath().string()));
  DriveCar(o, SetUpCar(ws, mesh, CarOptionsOf(o), "drive"), mesh, log, rep);
}

// ---- a road (ROAD/Graph.txt): the ground of the fragment the car is in and its neighbours ----

// Every file OUT depends on, on a road: Graph.txt, each fragment's model, mesh and record,
// CONTROLS, and the start fragment's metric record when the scale comes from it.
std::vector<fs::path> RoadDriveInputs(const DriveOptions& o, const Road& road) {
  std::vector<fs::path> inputs{road.GraphPath(), Road::PathFileOf(road.root())};
  for (const RoadFragment& f : road.fragments()) {
    const Workspace ws(f.dir);
    for (fs::path& p : ws.SparseModelFiles()) inputs.push_back(std::move(p));
    inputs.push_back(ws.MeshPath());
    inputs.push_back(Road::RecordPath(f.dir));
    if (o.scale == 0 && !o.metric) {
      const fs::path record = ws.MetricRecord("drive");  // (reads every provenance record)
      if (!record.empty()) inputs.push_back(record);
    }
  }
  if (!o.controls.empty()) inputs.emplace_back(o.controls);
  return inputs;
}

// Drives the car along a road and writes OUT. The car is set up as on a workspace (drive/
// car_setup.h) with the road's recorded drive: up from all of its cameras, the height from those
// over the start's ground, the scale from the start fragment's workspace.
void MakeRoadDrive(const DriveOptions& o, const Road& road, const ControlsLog& log,
                   DriveReport& rep) {
  const RoadLocator where(road);
  std::vector<size_t> homes;
  const RecordedDrive r = RoadRecordedDrive(where, o.pass, o.start, homes);
  RoadGround ground(where, homes[r.start]);
  const CarOnRoad set = SetUpRoadCar(where, ground, r, homes, CarOptionsOf(o), "drive");
  DriveCar(o, set, ground.ray(), log, rep,
           [&ground](const Eigen::Vector3d& c, double t) { return ground.Follow(c, t); });
  rep.fragments = ground.entered();
}

}  // namespace

OptionTable DeclareOptions(DriveOptions& o) {
  OptionTable t("drive");
  t.Positional("WS", &o.workspace,
               "Workspace folder (sparse/, mesh.ply), or a road folder (Graph.txt: roadsplit)")
      .Dir();
  t.OptionalPositional("CONTROLS", &o.controls,
                       "Controls log: a header naming 'time steer speed' (s, steering-wheel "
                       "degrees, m/s), then one row per sample; omitted with --lane-change")
      .File();
  t.OptionalPositional("OUT", &o.out, "Output trajectory file (tum, kitti) or folder (colmap)");
  t.Text("--lane-change", &o.lane_change,
         "T0:DURATION:OFFSET: drive the recorded path instead of CONTROLS, moving OFFSET metres "
         "to the left (+) or right (-) from T0 seconds for DURATION seconds")
      .Check([&o] {
        if (!o.lane_change.empty()) LaneChange::Parse(o.lane_change);
      });
  t.Real("--scale", &o.scale, "Model units per metre (1 for a metric workspace)").Check([&o] {
    if (o.scale != 0) CheckRange(o.scale, 0, 1e12, true, "--scale");  // 0: not given
  });
  t.Flag("--metric", &o.metric, "The workspace is in metres (--scale 1)");
  t.Real("--wheelbase", &o.wheelbase, "Rear to front axle, metres").Range(0.5, 20);
  t.Real("--steering-ratio", &o.steering_ratio, "Steering-wheel angle per road-wheel angle")
      .Range(1, 100);
  t.Real("--max-steer", &o.max_steer,
         "Largest road-wheel angle, degrees; larger ones are clamped (and counted)")
      .Range(0, 89, true);
  t.Real("--track", &o.track, "Left to right wheel, metres (where the ground is probed)")
      .Range(0.2, 5);
  t.Text("--camera-offset", &o.camera_offset,
         "X,Y,Z: the camera in metres forward, left and up of the ground under the rear axle "
         "centre (default 0,0,H: H the recorded cameras' median height above the mesh)")
      .Alternative("0,0,1.5")
      .Check([&o] {
        if (!o.camera_offset.empty()) ParseCameraOffset(o.camera_offset, "--camera-offset");
      });
  t.Text("--start", &o.start,
         "Start at this workspace image's pose (default: the first, in name order)");
  t.Text("--pass", &o.pass,
         "The recorded images are those whose names start with this (one drive of the road; "
         "default: all)");
  t.Real("--frame-rate", &o.frame_rate,
         "--lane-change: recorded images per second (image k is at k/HZ seconds)")
      .Range(0, 1000, true);
  t.Real("--rate", &o.rate, "Output poses per second").Range(0, 1000, true);
  t.Choice("--format", &o.format, kDriveFormats,
           "tum: TUM file; kitti: KITTI poses file; colmap: a COLMAP text model folder "
           "(OUT/images.txt)")
      .Alternative("kitti");  // colmap: OUT is a folder, not the base run's file
  t.Flag("--force", &o.force, "Rewrite OUT even when it is up to date").Cosmetic();
  DeclareQuietOption(t, o.quiet);
  return t;
}

void DriveOptions::Check() const {
  CheckDeclared(*this);
  if (lane_change.empty() && controls.empty())
    throw UsageError("give CONTROLS, or --lane-change T0:DURATION:OFFSET");
  if (!lane_change.empty() && !controls.empty())
    throw UsageError("--lane-change drives the recorded path: give WS OUT, no CONTROLS");
  if (out.empty()) throw UsageError("OUT is required");
  if (scale != 0 && metric) throw UsageError("give --scale or --metric, not both");
}

DriveReport RunDrive(const DriveOptions& o) {
  o.Check();
  DriveReport rep;
  ControlsLog log;
  if (o.lane_change.empty()) log = ReadControlsTsv(o.controls);  // a bad log fails first, fast
  rep.ignored_columns = log.ignored;
  std::optional<Road> road;
  std::optional<Workspace> ws;
  if (Road::IsRoad(o.workspace)) {
    road.emplace(o.workspace);
  } else {
    ws.emplace(o.workspace);
    ws->Require("drive", {WsItem::kSparse, WsItem::kMesh});
  }
  const fs::path root = road ? road->root() : ws->root();
  const std::vector<fs::path> outputs = OutputFiles(o);
  rep.output = outputs.size() == 1 ? outputs[0].string() : outputs[1].string();
  DriveOptions resolved = o;
  const OptionTable table = DeclareOptions(resolved);
  Ledger ledger(RecordRoot(o, root), "drive", table,
                road ? RoadDriveInputs(o, *road) : DriveInputs(o, *ws), root);
  const bool stale = ledger.AnyStale(outputs, {}, o.force);
  rep.why = ledger.Summary();
  if (!stale) {
    rep.up_to_date = true;
    return rep;
  }
  if (road)
    MakeRoadDrive(o, *road, log, rep);
  else
    MakeDrive(o, *ws, log, rep);
  for (const fs::path& p : outputs) ledger.Done(p);
  ledger.Write({{"scale_used", rep.scale},
                {"scale_source", rep.scale_source},
                {"camera_height", rep.camera_height},
                {"poses", rep.poses}});
  return rep;
}

}  // namespace mvtm
