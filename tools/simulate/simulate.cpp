#include "simulate.h"

#include <SDL2/SDL.h>

#include <algorithm>
#include <array>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <limits>
#include <memory>
#include <nlohmann/json.hpp>
#include <optional>
#include <ostream>
#include <set>
#include <thread>

#include "base/atomic_file.h"
#include "base/error.h"
#include "base/text.h"
#include "base/version.h"
#include "cli/work.h"
#include "devices.h"
#include "drive/car_setup.h"
#include "drive/controls_tsv.h"
#include "drive/road_car.h"
#include "image/async_writer.h"
#include "index/view_selection.h"
#include "io/mesh_io.h"
#include "io/trajectory.h"
#include "render/effects_plan.h"
#include "render/renderer.h"
#include "screen.h"
#include "workspace/projector_sources.h"
#include "workspace/road.h"
#include "workspace/road_locator.h"
#include "workspace/workspace.h"

namespace mvtm {

namespace {

// The car: its scale, geometry, start and longitudinal dynamics (as drive's where they agree).
void DeclareCarOptions(OptionTable& t, SimulateOptions& o) {
  t.Real("--scale", &o.scale, "Model units per metre (1 for a metric workspace)").Check([&o] {
    if (o.scale != 0) CheckRange(o.scale, 0, 1e12, true, "--scale");
  });
  t.Flag("--metric", &o.metric, "The workspace is in metres (--scale 1)");
  t.Real("--wheelbase", &o.wheelbase, "Rear to front axle, metres").Range(0.5, 20);
  t.Real("--steering-ratio", &o.steering_ratio, "Steering-wheel angle per road-wheel angle")
      .Range(1, 100);
  t.Real("--max-steer", &o.max_steer, "Largest road-wheel angle, degrees").Range(0, 89, true);
  t.Real("--track", &o.track, "Left to right wheel, metres (where the ground is probed)")
      .Range(0.2, 5);
  t.Text("--camera-offset", &o.camera_offset,
         "X,Y,Z: the camera in metres forward, left and up of the ground under the rear axle "
         "centre (default 0,0,H: H the recorded cameras' median height above the mesh)")
      .Check([&o] {
        if (!o.camera_offset.empty()) ParseCameraOffset(o.camera_offset, "--camera-offset");
      });
  t.Text("--start", &o.start, "Start at this workspace image's pose (default: the first)");
  t.Text("--pass", &o.pass,
         "The recorded drive is the images whose names start with this (default: the start "
         "image's drive, its name's prefix before '_')");
  t.Real("--max-accel", &o.car.max_accel, "Acceleration at full throttle, m/s^2").Range(0.1, 20);
  t.Real("--max-brake", &o.car.max_brake, "Deceleration at full brake, m/s^2").Range(0.1, 20);
  t.Real("--drag", &o.car.drag, "Aerodynamic deceleration per squared speed, 1/m").Range(0, 1);
  t.Real("--max-speed", &o.max_speed, "Speed cap, km/h").Range(1, 400);
  t.Real("--sim-rate", &o.sim_rate, "Vehicle simulation steps per second").Range(10, 2000);
}

// Frame rate, quality and the renderer's effects (as ptmrender's where they agree).
void DeclareRenderOptions(OptionTable& t, SimulateOptions& o) {
  t.Real("--fps", &o.fps,
         "Target frame rate (pacing, adaptive quality; --as-fast: frames per "
         "simulated second)")
      .Range(1, 240);
  t.Flag("--no-adapt", &o.no_adapt, "Keep the quality level whatever the frame rate");
  t.Integer("--quality", &o.quality,
            "Start at this quality level: 0 full (render scale 1, --projectors, full mesh) ... 7 "
            "(render 0.5x, 1 projector, mesh simplified beyond 6 m); with --no-adapt, fixed")
      .Range(0, 7);
  t.Integer("--projectors", &o.projectors, "K: projectors tried per pixel, best first")
      .Range(1, 16);
  t.Real("--bias", &o.bias, "Occlusion bias, relative: occluded when z > depth*(1+B)")
      .Range(0, 1, false, true);
  t.Flag("--no-occlusion", &o.no_occlusion, "Never test projector depth");
  t.Flag("--no-skybox", &o.no_skybox, "Constant background instead of projected sky");
  t.Real("--sky-distance", &o.sky_distance, kSkyDistanceHelp).AtLeast(-1).Alternative("0");
  t.Flag("--no-masks", &o.no_masks, "Ignore masks/ (vehicles are projected too)");
  t.Flag("--no-exposure", &o.no_exposure, "Ignore exposure.tsv");
  t.Flag("--no-blend", &o.no_blend, "The first projector that sees a point, not a blend");
  t.Flag("--no-fill", &o.no_fill, "Constant background where nothing is seen");
  t.Flag("--no-seen-surfaces", &o.no_seen,
         "Ignore stereo/: never take what a projector's photo saw in front of the mesh");
}

}  // namespace

OptionTable DeclareOptions(SimulateOptions& o) {
  OptionTable t("simulate");
  t.Positional("WS", &o.workspace,
               "Workspace folder (sparse/, images/, mesh.ply; depth/, masks/, textures/ used "
               "when present), or a road folder (Graph.txt: roadsplit), streamed")
      .Dir();
  t.Text("--size", &o.size,
         "One screen's size WxH (default: the camera's); the camera's horizontal field of view "
         "is kept, the vertical follows the aspect")
      .Alternative("160x90")
      .Check([&o] {
        if (!o.size.empty()) ParseImageSize(o.size);
      });
  t.Integer("--screens", &o.screens, "Screens side by side, each rendered with its own yaw")
      .Range(1, 8);
  t.Real("--screen-yaw", &o.screen_yaw,
         "Degrees between neighbouring screens' cameras (0: the horizontal field of view)")
      .Range(0, 120);
  DeclareCarOptions(t, o);
  DeclareRenderOptions(t, o);
  t.Text("--record", &o.record,
         "Folder for controls.tsv, poses.tsv, poses.tum and summary.json of the session");
  t.Flag("--record-frames", &o.record_frames, "With --record: also the frames shown");
  t.Text("--replay", &o.replay,
         "Drive this controls log (time steer speed) through the loop instead of the devices")
      .File();
  t.Flag("--as-fast", &o.as_fast,
         "Do not wait for the clock: frames at simulation times t0 + k/FPS (needs --replay or "
         "--duration)");
  t.Real("--duration", &o.duration,
         "End after this many simulated seconds (0: until quit, or the end of --replay's log)")
      .Range(0, 1e6);
  t.Text("--virtual-input", &o.virtual_input,
         "Drive SDL's virtual joystick with this script ('time axis0 axis1 ...' rows)")
      .File();
  t.Text("--mapping", &o.mapping, "Input mapping file (JSON: axes, inversion, dead zones)").File();
  t.Real("--speed-limit", &o.speed_limit,
         "Speed limit for the summary's RMS excess and time over it, km/h (0: none)")
      .Range(0, 400);
  t.Choice("--off-road", &o.off_road, kOffRoads,
           "Off the mesh (or --max-offset): reset to the nearest recorded pose, or stop there");
  t.Choice("--at-end", &o.at_end, kAtEnds,
           "Past the recorded drive's end: stop the session, or loop to the start");
  t.Real("--max-offset", &o.max_offset,
         "Metres from the recorded path counted as off the road (0: only the mesh's edge)")
      .Range(0, 1000);
  t.Text("--screenshot", &o.screenshot,
         "Write the last frame shown, HUD included, as this PNG when the session ends");
  t.Flag("--no-hud", &o.no_hud, "No speedometer and steering bar (studies)");
  t.Flag("--no-window", &o.no_window,
         "Render without showing (benchmarks, batch replays); keyboard unavailable");
  t.Flag("--explain", &o.explain, "Print the effects plan as JSON and drive nothing").Cosmetic();
  t.Choice("--gl", &o.gl, GlBackendTable(), "OpenGL backend");
  DeclareQuietOption(t, o.quiet);
  return t;
}

void SimulateOptions::Check() const {
  CheckDeclared(*this);
  if (scale != 0 && metric) throw UsageError("give --scale or --metric, not both");
  if (as_fast && replay.empty() && duration == 0)
    throw UsageError("--as-fast needs --replay LOG or --duration S (it would never end)");
  if (record_frames && record.empty()) throw UsageError("--record-frames needs --record OUT");
  if (!replay.empty() && !virtual_input.empty())
    throw UsageError("give --replay or --virtual-input, not both");
}

namespace {

using Clock = std::chrono::steady_clock;
double Seconds(Clock::time_point a, Clock::time_point b) {
  return std::chrono::duration<double>(b - a).count();
}

// What the car drives: the car set on it as drive sets it (CarOnRoad), the ground it is placed
// on, and the recorded drive as a path in metres. On a workspace the ground is its whole mesh;
// on a road (ROAD/Graph.txt) it is the fragment the car is in and its neighbours (RoadGround),
// following the car.
struct Track : CarOnRoad {
  std::unique_ptr<MeshRaycaster> ray;  // a workspace's mesh
  std::unique_ptr<RoadLocator> where;  // a road
  std::unique_ptr<RoadGround> ground;
  std::vector<size_t> homes;           // a road: the fragment owning each recorded image
  std::unique_ptr<RecordedPath> path;  // the recorded camera feet
  std::vector<PlanarPose> rear;        // the rear axle under each recorded camera
  std::vector<size_t> along;           // the recorded images the path runs through
  BicycleParams bicycle;

  const MeshRaycaster& Ground() const { return ground ? ground->ray() : *ray; }
  // The ground after the car's camera reached `centre` at time t.
  const MeshRaycaster& Follow(const Eigen::Vector3d& centre, double t) {
    return ground ? *ground->Follow(centre, t) : *ray;
  }
  // The ground under recorded image i (the car put down there).
  const MeshRaycaster& GroundAt(size_t i) { return ground ? *ground->JumpTo(homes[i]) : *ray; }
};

// The recorded path, the rear axles and the bicycle of a track whose car is set.
void MeasureTrack(const SimulateOptions& o, Track& r) {
  // The car is set up as drive sets it up (the up axis and height from every recorded image of
  // --pass), but the path it is measured against is the start image's own drive (its name's
  // prefix before '_', without --pass), not every drive of the road in name order.
  const std::string own = o.pass.empty() ? PassOf(r.rec.images[r.rec.start]->name) : "";
  std::vector<Eigen::Vector2d> feet;
  for (size_t i = 0; i < r.rec.w2c.size(); ++i) {
    const PlanarPose foot = PlanarCamera(r.frame, r.rec.w2c[i]);
    r.rear.push_back(RearAxleUnder(foot, r.car));
    if (!own.empty() && PassOf(r.rec.images[i]->name) != own) continue;
    r.along.push_back(i);
    feet.emplace_back(foot.x, foot.y);
  }
  r.path = std::make_unique<RecordedPath>(feet);
  r.bicycle = BicycleParams{o.wheelbase, o.steering_ratio, o.max_steer};
}

CarOptions CarOptionsOf(const SimulateOptions& o) {
  return {o.scale, o.metric, o.wheelbase, o.track, o.camera_offset, o.pass, o.start};
}

Track LoadTrack(const SimulateOptions& o, const Workspace& ws, const Mesh& mesh) {
  Track r;
  r.ray = std::make_unique<MeshRaycaster>(mesh);
  static_cast<CarOnRoad&>(r) = SetUpCar(ws, *r.ray, CarOptionsOf(o), "simulate");
  MeasureTrack(o, r);
  return r;
}

Track LoadRoadTrack(const SimulateOptions& o, const Road& road) {
  Track r;
  r.where = std::make_unique<RoadLocator>(road);
  const RecordedDrive drive = RoadRecordedDrive(*r.where, o.pass, o.start, r.homes);
  r.ground = std::make_unique<RoadGround>(*r.where, r.homes[drive.start], /*keep_mesh=*/true);
  static_cast<CarOnRoad&>(r) =
      SetUpRoadCar(*r.where, *r.ground, drive, r.homes, CarOptionsOf(o), "simulate");
  MeasureTrack(o, r);
  return r;
}

// The camera's foot point (planar metres) of a car whose rear axle is at `rear`.
Eigen::Vector2d FootOf(const PlanarPose& rear, const CarGeometry& car) {
  const double c = std::cos(rear.heading), s = std::sin(rear.heading);
  const Eigen::Vector3d& off = car.camera_offset;
  return {rear.x + c * off.x() - s * off.y(), rear.y + s * off.x() + c * off.y()};
}

// The car as it drives: its path (a segment per reset), its ground and its speed.
class LiveCar {
 public:
  LiveCar(Track& road, const PlanarPose& rear, double t) : road_(road) { Restart(rear, t); }
  // Puts the car at `rear`, standing, from time t: a new segment. `ground` (metres along up;
  // NaN: the start's) is the ground height there, where the wheels' rays start from.
  void Restart(const PlanarPose& rear, double t, double ground = std::nan("")) {
    path_ = std::make_unique<SteeredPath>(std::vector<ControlSample>{{t, 0, 0, 0}}, road_.bicycle,
                                          rear);
    placer_ = std::make_unique<GroundPlacer>(road_.Ground(), road_.frame, road_.car);
    if (!std::isnan(ground)) placer_->StartFromGround(ground);
    speed_ = 0;
    steer_ = 0;
  }
  // The controls from time t on; appended to the path when they change (or `always`). True
  // when appended.
  bool Control(double t, double steer, double speed, bool always) {
    if (!always && steer == steer_ && speed == speed_) return false;
    if (t > path_->end_time())
      path_->Append({t, steer, speed, 0});
    else  // the segment's first sample (a restart at t): replace it
      path_ = std::make_unique<SteeredPath>(std::vector<ControlSample>{{t, steer, speed, 0}},
                                            road_.bicycle, path_->At(t));
    steer_ = steer;
    speed_ = speed;
    return true;
  }
  PlanarPose At(double t) const { return path_->Continued(t); }
  // The car placed at time t; on a road, the next placement is on the ground of the fragment
  // its camera is in now.
  Placement Place(double t) {
    const Placement p = placer_->Place(At(t), t);
    if (road_.ground) placer_->UseMesh(road_.Follow(p.camera_to_world.t, t));
    return p;
  }
  double speed() const { return speed_; }
  double steer() const { return steer_; }
  double segment_start() const { return path_->start_time(); }

 private:
  Track& road_;
  std::unique_ptr<SteeredPath> path_;
  std::unique_ptr<GroundPlacer> placer_;
  double speed_ = 0, steer_ = 0;
};

// The session's files, written as it goes under OUT/.NAME.partial, renamed at the end.
class Recorder {
 public:
  explicit Recorder(const std::string& dir) : dir_(dir) {
    if (dir_.empty()) return;
    CreateFolder(dir_);
    for (Log* l : logs()) {
      l->out.open(Partial(l->name));
      if (!l->out) throw Error(dir_.string(), 0, "cannot write the session's files");
    }
    // A session's frames are its own: an earlier, longer session's are not left beside them.
    std::error_code ec;
    fs::remove_all(dir_ / "frames", ec);
    Write(controls_, [](std::ofstream& f) { f << "time\tsteer\tspeed\tthrottle\tbrake\n"; });
    Write(poses_, [](std::ofstream& f) {
      f << "# time tx ty tz qx qy qz qw display_time (camera-to-world; time: simulation seconds; "
           "display_time: wall seconds since the start)\n";
    });
    Write(tum_,
          [](std::ofstream& f) { f << "# timestamp tx ty tz qx qy qz qw (camera-to-world)\n"; });
  }
  bool on() const { return !dir_.empty(); }
  // A controls row; one at the time of the row before replaces it (a segment's first sample
  // replaced in the same step), so times strictly increase.
  void Control(double t, double steer, double speed, const Pedals& p) {
    if (!on()) return;
    if (pending_ && pending_time_ < t) Flush();
    pending_ = true;
    pending_time_ = t;
    pending_row_ = FormatDouble(t) + '\t' + FormatDouble(steer) + '\t' + FormatDouble(speed) +
                   '\t' + FormatDouble(p.throttle) + '\t' + FormatDouble(p.brake) + '\n';
  }
  // A reset at t: a pending row at t (the car's controls before it) is dropped, so the row the
  // reset writes next is the only one at t.
  void Restart(double t) {
    if (pending_ && pending_time_ >= t) pending_ = false;
    Flush();
  }
  void Comment(const std::string& text) {
    if (!on()) return;
    Flush();
    Write(controls_, [&](std::ofstream& f) { f << "# " << text << '\n'; });
  }
  void Pose(double t, const Rigid3d& c2w, double display) {
    if (!on()) return;
    const std::string row = TumRow(t, c2w);
    Write(poses_, [&](std::ofstream& f) { f << row << ' ' << FormatDouble(display) << '\n'; });
    Write(tum_, [&](std::ofstream& f) { f << row << '\n'; });
    if (Clock::now() - flushed_ > std::chrono::seconds(1)) {  // a crash keeps all but a second
      for (Log* l : logs()) Write(*l, [](std::ofstream& f) { f.flush(); });
      flushed_ = Clock::now();
    }
  }
  // Frame n as shown: NNNNNN.png, or with several screens NNNNNN_sK.png (K from the left).
  void Frame(size_t n, std::vector<Image> screens) {
    if (!on()) return;
    for (size_t k = 0; k < screens.size(); ++k) {
      char name[48];
      if (screens.size() == 1)
        std::snprintf(name, sizeof name, "%06zu.png", n);
      else
        std::snprintf(name, sizeof name, "%06zu_s%zu.png", n, k);
      writer_.Push((dir_ / "frames" / name).string(), std::move(screens[k]), PngCompression::kFast);
    }
  }
  // Closes the files and renames them into place; writes summary.json.
  void Finish(const nlohmann::json& summary) {
    if (!on()) return;
    Flush();
    writer_.Finish();
    for (Log* l : logs()) Write(*l, [](std::ofstream& f) { f.close(); });
    for (Log* l : logs()) {
      SyncFile(Partial(l->name), dir_ / l->name);  // on the disk before the final name shows it
      std::error_code ec;
      fs::rename(Partial(l->name), dir_ / l->name, ec);
      if (ec) throw Error((dir_ / l->name).string(), 0, "cannot write: " + ec.message());
    }
    SyncFolder(dir_);
    WriteTextAtomic(dir_ / "summary.json", [&](std::ostream& f) { f << summary.dump(2) << '\n'; });
  }

 private:
  fs::path Partial(const std::string& name) const { return dir_ / ("." + name + ".partial"); }
  void Flush() {
    if (pending_) Write(controls_, [&](std::ofstream& f) { f << pending_row_; });
    pending_ = false;
  }
  // One of the session's logs, written as OUT/.NAME.partial.
  struct Log {
    std::ofstream out;
    const char* name;
  };
  std::array<Log*, 3> logs() { return {&controls_, &poses_, &tum_}; }
  // Runs `op` on the log's stream; a failure (with its reason, StreamFailure) stops the session
  // there: a record with rows missing is no record of it.
  template <class Op>
  void Write(Log& l, Op op) {
    const int err = StreamFailure(l.out, [&] { op(l.out); });
    if (l.out.fail()) throw WriteFailed(dir_ / l.name, err);
  }
  fs::path dir_;
  bool pending_ = false;
  double pending_time_ = 0;
  std::string pending_row_;
  Log controls_{{}, "controls.tsv"}, poses_{{}, "poses.tsv"}, tum_{{}, "poses.tum"};
  AsyncImageWriter writer_;
  Clock::time_point flushed_ = Clock::now();
};

// Adaptive quality: levels of (render scale, projectors, level-of-detail distance in metres; 0:
// full detail), full first.
class Quality {
 public:
  struct Level {
    double scale;
    int projectors;
    double lod_m;
    bool operator!=(const Level& o) const {
      return scale != o.scale || projectors != o.projectors || lod_m != o.lod_m;
    }
  };
  Quality(int projectors, double fps, bool adapt, int start) : budget_(1 / fps), adapt_(adapt) {
    const int k = projectors, two = std::min(k, 2);
    const Level all[] = {{1, k, 0},     {1, two, 0},  {1, two, 40}, {0.75, two, 40},
                         {0.75, 1, 25}, {0.5, 1, 25}, {0.5, 1, 12}, {0.5, 1, 6}};
    for (const Level& l : all)
      if (levels_.empty() || levels_.back() != l) levels_.push_back(l);
    level_ = std::min(start, levels() - 1);
  }
  double scale() const { return levels_[size_t(level_)].scale; }
  int projectors() const { return levels_[size_t(level_)].projectors; }
  double lod_m() const { return levels_[size_t(level_)].lod_m; }
  // The level-of-detail distances the session may use (all levels' when adapting).
  std::vector<double> DetailDistances() const {
    std::vector<double> d;
    for (size_t i = 0; i < levels_.size(); ++i)
      if (levels_[i].lod_m > 0 && (adapt_ || int(i) == level_)) d.push_back(levels_[i].lod_m);
    std::sort(d.begin(), d.end());
    d.erase(std::unique(d.begin(), d.end()), d.end());
    return d;
  }
  int level() const { return level_; }
  int levels() const { return int(levels_.size()); }
  // After a frame that took `seconds` (render and show): a change, or none.
  std::optional<QualityChange> Update(double seconds, double t) {
    mean_ = frames_ == 0 ? seconds : 0.8 * mean_ + 0.2 * seconds;
    ++frames_;
    if (!adapt_) return std::nullopt;
    int to = level_;
    // Far over budget, a level down after 3 frames (the first frames compile shaders and read
    // projectors: a start, not a trend); just over it, after 10.
    const int settle = mean_ > 2 * budget_ ? 3 : 10;
    // Down at 90 % of the budget: the headroom absorbs a projector read or a reset's reload.
    if (mean_ > 0.9 * budget_ && frames_ >= settle && level_ + 1 < levels()) to = level_ + 1;
    if (mean_ < 0.45 * budget_ && frames_ >= 60 && level_ > 0) to = level_ - 1;
    if (to == level_) return std::nullopt;
    char why[96];
    std::snprintf(why, sizeof why, "%.1f ms per frame against a %.1f ms budget", mean_ * 1e3,
                  budget_ * 1e3);
    level_ = to;
    frames_ = 0;
    return QualityChange{t, level_, scale(), projectors(), lod_m(), why};
  }

 private:
  std::vector<Level> levels_;
  double budget_;
  bool adapt_;
  int level_ = 0, frames_ = 0;
  double mean_ = 0;
};

// One screen's camera: the model's camera at W x H keeping its horizontal field of view.
Camera ScreenCamera(const Reconstruction& rec, const std::string& size) {
  const Camera base = rec.RenderCamera();
  if (size.empty()) return base;
  const ImageSize s = ParseImageSize(size);
  const double k = double(s.width) / double(base.width);
  Camera c;
  c.id = base.id;
  c.model = CameraModel::kPinhole;
  c.width = s.width;
  c.height = s.height;
  c.params = {base.fx() * k, base.fy() * k, s.width / 2.0 + (base.cx() - base.width / 2.0) * k,
              s.height / 2.0 + (base.cy() - base.height / 2.0) * k};
  return c;
}

// ptmrender's rendering of the workspace, for live views.
class LiveView {
 public:
  // `scene_far`: the scene's far end (SceneFarEnd of the model with its points).
  LiveView(const SimulateOptions& o, const Workspace& ws, const Reconstruction& rec,
           const Mesh& mesh, double scale, double scene_far)
      : o_(o),
        ws_(ws),
        rec_(rec),
        images_(rec.ImagesByName()),
        renderer_(mesh),
        sources_(ws, rec, images_, &renderer_, /*prefer_textures=*/true),
        scale_(scale),
        scene_far_(scene_far) {
    for (const ImageRecord* im : images_) candidates_.push_back(im->world_to_camera);
    screen_ = ScreenCamera(rec, o.size);
    const double hfov = 2 * std::atan(screen_.width / (2 * screen_.fx())) * 180 / M_PI;
    screen_yaw_ = o.screen_yaw > 0 ? o.screen_yaw : hfov;
  }
  const Camera& screen() const { return screen_; }
  // Builds the simplified meshes of these level-of-detail distances (metres) now, so a level
  // change in the session costs no rebuild. The seconds it took.
  double PrepareDetail(const std::vector<double>& distances_m) {
    const auto t0 = Clock::now();
    for (double d : distances_m) renderer_.SetDetail(d * scale_, d * scale_ / 25);
    renderer_.SetDetail(0, 0);
    lod_m_ = 0;
    return Seconds(t0, Clock::now());
  }
  // The survey and plan from the start view and recorded views along the drive.
  void Plan(const Rigid3d& start_c2w, const std::vector<Rigid3d>& recorded_w2c);
  // Goes on from `prev` (the view of the fragment the car left): its survey and plan (a road has
  // one plan, upgraded live as on a workspace; the sky is put at this fragment's own far end, as
  // ptmrender does on a road) and its totals.
  // The level of detail in use is built now (the first frame would otherwise).
  void Adopt(const LiveView& prev) {
    survey_ = prev.survey_;
    survey_.scene_far = scene_far_;
    plan_ = PlanEffects(survey_);
    stats_ = prev.stats_;
    load_ms_ = prev.load_ms_;
    if (prev.lod_m_ > 0) renderer_.SetDetail(prev.lod_m_ * scale_, prev.lod_m_ * scale_ / 25);
    lod_m_ = prev.lod_m_;
  }
  const SceneSurvey& survey() const { return survey_; }
  const EffectsPlan& plan() const { return plan_; }
  const RenderStats& stats() const { return stats_; }  // totals over every render
  double load_ms() const { return load_ms_; }          // choosing and reading projectors, in total
  // Renders every screen at the car's camera pose; `log` gets plan upgrades.
  std::vector<Image> Render(const Rigid3d& c2w, const Quality& q, double ahead_m,
                            std::vector<std::string>& log);

 private:
  std::vector<size_t> Pick(const Rigid3d& w2c, int k) const {
    ViewSelectionOptions so;
    so.k = size_t(k);
    std::vector<size_t> idx;
    for (const Candidate& c : SelectViews(w2c, candidates_, so)) idx.push_back(c.index);
    return idx;
  }
  Image RenderOne(const Rigid3d& w2c, const Camera& cam, int k, bool survey,
                  std::vector<std::string>& log);

  const SimulateOptions& o_;
  const Workspace& ws_;
  const Reconstruction& rec_;
  std::vector<const ImageRecord*> images_;
  std::vector<Rigid3d> candidates_;
  Renderer renderer_;
  ProjectorSources sources_;
  double scale_;      // model units per metre
  double scene_far_;  // the scene's far end (SceneFarEnd), model units
  double lod_m_ = 0;  // the level of detail in use (metres; 0: full)
  Camera screen_;
  double screen_yaw_ = 0;
  SceneSurvey survey_;
  EffectsPlan plan_;
  RenderStats stats_;
  double load_ms_ = 0;
};

void LiveView::Plan(const Rigid3d& start_c2w, const std::vector<Rigid3d>& recorded_w2c) {
  SceneSurvey& s = survey_;
  s.ptm = true;
  s.projectors_requested = o_.projectors;
  s.bias = o_.bias;
  s.no_occlusion = o_.no_occlusion;
  s.no_masks = o_.no_masks;
  s.no_skybox = o_.no_skybox;
  s.no_exposure = o_.no_exposure;
  s.no_blend = o_.no_blend;
  s.no_fill = o_.no_fill;
  s.no_seen = o_.no_seen;
  s.sky_distance = o_.sky_distance;
  s.scene_far = scene_far_;
  s.projector_differs = true;  // a live car is never exactly at a recorded pose
  s.several_admissible = o_.projectors > 1 && images_.size() > 1;
  std::set<size_t> all;
  for (size_t i = 0; i < images_.size(); ++i) all.insert(i);
  if (!o_.no_masks) s.mask_example = FirstMaskedImage(ws_, images_, all);
  if (!o_.no_exposure) s.exposure_example = FirstExposedImage(ws_, images_, all);
  if (!o_.no_seen) s.seen_example = FirstSeenImage(ws_, images_, all);
  std::vector<std::pair<Rigid3d, std::string>> views = {{start_c2w.Inverse(), "the start view"}};
  const size_t n = recorded_w2c.size(), step = std::max<size_t>(1, n / 8);
  for (size_t i = 0; i < n; i += step)
    views.push_back({recorded_w2c[i], "recorded view " + std::to_string(i)});
  for (const auto& [w2c, name] : views) {
    const std::vector<size_t> idx = Pick(w2c, 1);
    std::optional<View> first;
    if (!idx.empty()) first = sources_.ViewOf(idx[0]);
    AddToSurvey(s, SurveyView(renderer_, View{screen_, w2c}, first ? &*first : nullptr), name);
  }
  plan_ = PlanEffects(s);
}

Image LiveView::RenderOne(const Rigid3d& w2c, const Camera& cam, int k, bool survey,
                          std::vector<std::string>& log) {
  const auto t0 = Clock::now();
  sources_.Trim();
  const std::vector<size_t> idx = Pick(w2c, k);
  const std::vector<Projector> ps = GatherProjectors(sources_, idx, plan_);
  load_ms_ += Seconds(t0, Clock::now()) * 1e3;
  const CameraExposure exposure =
      plan_.exposure ? ExposureNear(ps, w2c.Centre()) : CameraExposure();
  const View view{cam, w2c};
  Renderer::Frame f = renderer_.Render(view, ps, plan_, &stats_, survey, exposure);
  if (survey) {  // a hole the survey did not foresee turns the skybox and fill on from now
    AddToSurvey(survey_, CoverageOf(f.depth, view, ps.empty() ? nullptr : &ps[0].view),
                "a live view");
    const EffectsPlan now = PlanEffects(survey_);
    if (now.skybox != plan_.skybox || now.fill != plan_.fill)
      log.push_back(std::string("plan: a live view sees no surface somewhere: skybox ") +
                    (now.skybox ? "on" : "off") + ", fill " + (now.fill ? "on" : "off"));
    plan_ = now;
  }
  return std::move(f.colour);
}

std::vector<Image> LiveView::Render(const Rigid3d& c2w, const Quality& q, double ahead_m,
                                    std::vector<std::string>& log) {
  if (q.lod_m() != lod_m_) {  // cells a 25th of the distance: a constant angular error
    renderer_.SetDetail(q.lod_m() * scale_, q.lod_m() * scale_ / 25);
    lod_m_ = q.lod_m();
  }
  const uint64_t w = std::max<uint64_t>(1, uint64_t(std::lround(screen_.width * q.scale())));
  const uint64_t h = std::max<uint64_t>(1, uint64_t(std::lround(screen_.height * q.scale())));
  const Camera cam = q.scale() == 1 ? screen_ : screen_.Scaled(w, h);
  std::vector<Image> frames;
  const bool survey = !(plan_.skybox && plan_.fill) && !(o_.no_skybox && o_.no_fill);
  for (int i = 0; i < o_.screens; ++i) {
    const double yaw = ((o_.screens - 1) / 2.0 - i) * screen_yaw_;
    frames.push_back(RenderOne(yaw == 0 ? c2w.Inverse() : MovedAndTurned(c2w.Inverse(), 0, yaw),
                               cam, q.projectors(), survey && i == 0, log));
  }
  // Read ahead: the projectors of where the car will be (straight on) in half a second.
  Rigid3d ahead = c2w;
  ahead.t += c2w.R().col(2) * ahead_m;
  sources_.Prefetch(Pick(ahead.Inverse(), q.projectors()), plan_.occlusion || plan_.skybox,
                    plan_.masks, plan_.SeenProjectors());
  return frames;
}

// The view the car's camera is rendered in: one for a workspace; on a road, the view of the
// fragment the car's ground is in (that fragment's photos as projectors, the mesh the ground
// holds: its own and its neighbours' triangles), made when the car enters it and going on with
// the road's plan.
class Views {
 public:
  Views(const SimulateOptions& o, Track& track) : o_(o), track_(track) {}
  // A workspace's view (`ws` outlives it).
  void Open(const Workspace& ws, const Reconstruction& rec, const Mesh& mesh) {
    view_ = std::make_unique<LiveView>(o_, ws, rec, mesh, track_.scale, SceneFarEnd(rec));
  }
  // A road's view of the fragment the car starts in.
  void OpenRoad() { view_ = MakeFragmentView(track_.ground->home()); }
  LiveView& view() { return *view_; }
  // The view for the car where its ground is now (on a road, made anew when it entered another
  // fragment; `log` says so).
  LiveView& Current(double t, std::vector<std::string>& log) {
    if (!track_.ground || track_.ground->home() == home_) return *view_;
    const auto t0 = Clock::now();
    std::unique_ptr<Workspace> old_ws = std::move(ws_);
    std::unique_ptr<LiveView> next = MakeFragmentView(track_.ground->home());
    next->Adopt(*view_);
    view_ = std::move(next);
    old_ws.reset();
    char note[160];
    std::snprintf(note, sizeof note, "t=%s s: fragment %s entered: its view made in %.0f ms",
                  FormatShort(std::round(t * 1000) / 1000).c_str(),
                  track_.where->road().fragments()[home_].id.c_str(),
                  Seconds(t0, Clock::now()) * 1e3);
    log.push_back(note);
    return *view_;
  }

 private:
  std::unique_ptr<LiveView> MakeFragmentView(size_t home) {
    home_ = home;
    ws_ = std::make_unique<Workspace>(track_.where->road().fragments()[home].dir);
    return std::make_unique<LiveView>(o_, *ws_, track_.where->model(home), track_.ground->mesh(),
                                      track_.scale, track_.where->far_end(home));
  }

  const SimulateOptions& o_;
  Track& track_;
  std::unique_ptr<Workspace> ws_;  // a road: the fragment's
  std::unique_ptr<LiveView> view_;
  size_t home_ = 0;
};

// Where the projectors' depth maps come from, when the plan needs them ("" when it does not).
std::string DepthSource(const Workspace& ws, const Reconstruction& rec, const EffectsPlan& plan) {
  if (!(plan.occlusion || plan.skybox)) return "";
  size_t baked = 0, n = 0;
  for (const ImageRecord* im : rec.ImagesByName()) {
    ++n;
    baked += fs::exists(ws.DepthPath(im->name));
  }
  const std::string counts = std::to_string(baked) + " of " + std::to_string(n);
  if (baked == n) return "depth maps: all " + std::to_string(n) + " baked (WS/depth/)";
  return "depth maps: " + counts +
         " baked; the others are rendered from the mesh when a projector is first used (a "
         "depth pass each, on the render thread; `bakedepth WS` makes them once)";
}

// SDL for the session's lifetime.
struct SdlSession {
  explicit SdlSession(bool video) {
    SDL_SetHint(SDL_HINT_JOYSTICK_ALLOW_BACKGROUND_EVENTS, "1");  // a study runs other windows
    // The window's pixels are copied in software: an accelerated window framebuffer would make
    // SDL's own GL context current on this thread, under the renderer's.
    SDL_SetHint(SDL_HINT_FRAMEBUFFER_ACCELERATION, "0");
    const Uint32 flags = SDL_INIT_JOYSTICK | SDL_INIT_GAMECONTROLLER | (video ? SDL_INIT_VIDEO : 0);
    if (SDL_Init(flags) != 0)
      throw Error(
          std::string("SDL cannot start") + (video ? " a window" : "") + ": " + SDL_GetError() +
          (video ? " (no display? SDL_VIDEODRIVER=offscreen, xvfb-run, or --no-window)" : ""));
  }
  ~SdlSession() { SDL_Quit(); }
  SdlSession(const SdlSession&) = delete;
  SdlSession& operator=(const SdlSession&) = delete;
};

// The running session: the car, its input, the screens, the record.
class Session {
 public:
  Session(const SimulateOptions& o, Track& road, Views& views, Devices& devices, Screen* screen,
          Recorder& rec, const ControlsLog* log, SimulateReport& rep)
      : o_(o),
        road_(road),
        views_(views),
        devices_(devices),
        screen_(screen),
        rec_(rec),
        log_(log),
        rep_(rep),
        quality_(o.projectors, o.fps, !o.no_adapt, o.quality),
        measures_(o.speed_limit / 3.6),
        t0_(log ? log->samples.front().time : 0),
        car_(road, road.rear[road.rec.start], t0_) {
    lp_ = o.car;
    lp_.max_speed = o.max_speed / 3.6;
    t_end_ = log ? log->samples.back().time : std::numeric_limits<double>::infinity();
    if (o.duration > 0) t_end_ = std::min(t_end_, t0_ + o.duration);
    t_last_ = t0_;
    last_shown_ = t0_;
    last_good_ = road.rear[road.rec.start];
    hud_ = !o.no_hud;
    rec_.Control(t0_, 0, 0, Pedals());
    if (log_) Apply(log_->samples[next_sample_++]);
    const std::vector<double> detail = quality_.DetailDistances();
    if (!detail.empty()) {
      char note[96];
      std::snprintf(note, sizeof note, "levels of detail for %zu distances prepared in %.2f s",
                    detail.size(), views_.view().PrepareDetail(detail));
      rep_.log.push_back(note);
    }
  }
  void Run();

 private:
  void Apply(const ControlSample& c) {
    car_.Control(c.time, c.steer_deg, c.speed, true);
    rec_.Control(c.time, c.steer_deg, c.speed, Pedals());
  }
  double NextStepTime() const {
    double t = t0_ + double(k_ + 1) / o_.sim_rate;
    if (log_ && next_sample_ < log_->samples.size())
      t = std::min(t, log_->samples[next_sample_].time);
    return t;
  }
  void Step(double t);
  void Reset(double t, const std::string& why, bool to_start);
  bool Frame(double T, double display);  // false: the session ends

  const SimulateOptions& o_;
  Track& road_;
  Views& views_;
  Devices& devices_;
  Screen* screen_;
  Recorder& rec_;
  const ControlsLog* log_;
  SimulateReport& rep_;
  Quality quality_;
  DrivingMeasures measures_;
  LongitudinalParams lp_;
  double t0_, t_end_ = 0, t_last_ = 0, offset_ = 0;
  LiveCar car_;
  long k_ = 0;
  size_t next_sample_ = 0;
  Pedals pedals_;
  PlanarPose last_good_;
  double last_ground_ = std::nan("");  // metres along up under the rear axle, last frame
  double last_shown_ = 0;              // the simulation time of the last frame shown
  bool hud_ = true, ended_ = false;
  std::vector<Image> last_frames_;  // --screenshot without a window: the last frame's screens
  HudState last_hud_;

 public:
  // The last frame as the window shows it (without a window: as it would), HUD included.
  Image Screenshot() const {
    if (screen_) return screen_->Capture();
    std::vector<const Image*> ptrs;
    for (const Image& f : last_frames_) ptrs.push_back(&f);
    if (ptrs.empty()) return Image();
    return Compose(ptrs, int(views_.view().screen().width) * o_.screens,
                   int(views_.view().screen().height), hud_ ? &last_hud_ : nullptr);
  }
};

void Session::Step(double t) {
  measures_.Add(t - t_last_, car_.speed(), offset_);
  if (t >= t0_ + double(k_ + 1) / o_.sim_rate) ++k_;
  if (log_) {
    while (next_sample_ < log_->samples.size() && log_->samples[next_sample_].time <= t)
      Apply(log_->samples[next_sample_++]);
  } else {
    pedals_ = devices_.Sample(t, 1 / o_.sim_rate);
    const double v = NextSpeed(car_.speed(), pedals_, 1 / o_.sim_rate, lp_);
    if (car_.Control(t, pedals_.steer_deg, v, false))
      rec_.Control(t, pedals_.steer_deg, v, pedals_);
  }
  t_last_ = t;
  ++rep_.steps;
  const PathPoint pp = road_.path->Project(FootOf(car_.At(t), road_.car));
  offset_ = pp.offset;
  if (pp.along >= pp.length - 0.05 && car_.speed() > 0) {
    if (o_.at_end == AtEnd::kStop) {
      ended_ = true;
      rep_.ended = "the end of the recorded drive";
    } else {
      Reset(t, "the end of the recorded drive: back to the start", true);
    }
  } else if (o_.max_offset > 0 && std::abs(offset_) > o_.max_offset) {
    Reset(t,
          FormatShort(std::round(std::abs(offset_) * 100) / 100) +
              " m from the recorded path (--max-offset)",
          false);
  }
}

void Session::Reset(double t, const std::string& why, bool to_start) {
  PlanarPose at = last_good_;
  double ground = last_ground_;
  std::string where = "where it last was on the road";
  if (to_start || o_.off_road == OffRoad::kReset) {
    const size_t i = to_start ? road_.rec.start
                              : road_.along[road_.path->Nearest(FootOf(car_.At(t), road_.car))];
    at = road_.rear[i];
    where = road_.rec.images[i]->name;
    // The recorded camera's height less the car's camera height: the ground under it.
    ground = road_.frame.Height(road_.rec.w2c[i].Centre()) - road_.car.camera_offset.z();
    road_.GroundAt(i);  // on a road, that image's fragment
  }
  car_.Restart(at, t, ground);
  rec_.Restart(t);  // this step's row (if any) is the car's before the reset: dropped
  // A replayed log goes on with its current sample (its speed is taken as it is) from the pose
  // the car was put at; stopped (--off-road stop), the car stands until the log's next sample.
  if (log_ && next_sample_ > 0 && (to_start || o_.off_road == OffRoad::kReset)) {
    const ControlSample& c = log_->samples[next_sample_ - 1];
    car_.Control(t, c.steer_deg, c.speed, true);
  }
  measures_.Reset();
  rec_.Comment("reset at " + FormatDouble(t) + " s to " + where + ": " + why);
  rec_.Control(t, car_.steer(), car_.speed(), Pedals());
  rep_.log.push_back("t=" + FormatShort(std::round(t * 1000) / 1000) + " s: car put " +
                     (where.find(' ') == std::string::npos ? "at " : "") + where + ": " + why);
  offset_ = road_.path->Project(FootOf(at, road_.car)).offset;
}

bool Session::Frame(double T, double display) {
  const auto t_start = Clock::now();
  const InputEvents ev = devices_.Poll();
  for (const std::string& l : ev.log)
    rep_.log.push_back("t=" + FormatShort(std::round(T * 1000) / 1000) + " s: " + l);
  if (ev.quit) {
    rep_.quit = true;
    rep_.ended = "quit";
    return false;
  }
  if (ev.toggle_hud) hud_ = !hud_;
  for (double next = NextStepTime(); next <= T && !ended_; next = NextStepTime()) Step(next);
  if (ev.reset) Reset(T, "Backspace", false);
  Placement p;
  try {
    p = car_.Place(T);
  } catch (const Error& e) {
    Reset(T, std::string("off the mesh (") + e.what() + ")", false);
    p = car_.Place(T);
  }
  last_good_ = car_.At(T);
  last_ground_ = road_.frame.Height(p.rear_ground);
  const auto t_render = Clock::now();
  std::vector<Image> frames =
      views_.Current(T, rep_.log)
          .Render(p.camera_to_world, quality_, std::max(0.0, car_.speed()) * 0.5 * road_.scale,
                  rep_.log);
  rep_.render_ms += Seconds(t_render, Clock::now()) * 1e3;
  const HudState hs{car_.speed() * 3.6, car_.steer(), pedals_.reverse, quality_.level(),
                    quality_.levels()};
  std::vector<const Image*> ptrs;
  for (const Image& f : frames) ptrs.push_back(&f);
  if (screen_) screen_->Show(ptrs, hud_ ? &hs : nullptr);
  if (!o_.screenshot.empty() && !screen_) {  // kept for the end: the last frame's
    last_frames_ = frames;
    last_hud_ = hs;
  }
  rec_.Pose(T, p.camera_to_world, display);
  last_shown_ = T;
  if (o_.record_frames) {  // as shown: each screen at the screen's size (nearest, as the window)
    std::vector<Image> shown;
    const int w = int(views_.view().screen().width), h = int(views_.view().screen().height);
    for (const Image& f : frames)
      shown.push_back(f.width == w && f.height == h ? f : Compose({&f}, w, h, nullptr));
    rec_.Frame(rep_.frames, std::move(shown));
  }
  ++rep_.frames;
  if (auto c = quality_.Update(Seconds(t_start, Clock::now()), T)) rep_.quality.push_back(*c);
  return !ended_ && T < t_end_;
}

void Session::Run() {
  const auto wall0 = Clock::now();
  const double budget = 1 / o_.fps;
  double T = t0_;
  if (o_.as_fast) {
    const std::vector<double> times = SampleTimes(t0_, t_end_, o_.fps);
    for (double t : times) {
      T = t;
      if (!Frame(t, Seconds(wall0, Clock::now()))) break;
    }
  } else {
    // Frames on a fixed cadence of deadlines: a late frame is followed by a shorter wait, so
    // the rate holds when frames take less than the budget on average; one far behind (more
    // than three frames) starts the cadence again from now instead of rushing to catch up.
    const auto period =
        std::chrono::duration_cast<Clock::duration>(std::chrono::duration<double>(budget));
    auto deadline = wall0;
    for (;;) {
      const auto frame_start = Clock::now();
      T = std::min(t_end_, t0_ + Seconds(wall0, frame_start));
      if (!Frame(T, Seconds(wall0, frame_start))) break;
      deadline += period;
      const auto now = Clock::now();
      if (now > deadline + 3 * period) deadline = now;
      std::this_thread::sleep_until(deadline);
    }
  }
  // The log ends at the last frame shown, so drive's path ends where the session did.
  // (A quit ends at the frame before it: the quitting frame is never shown.)
  T = last_shown_;
  if (!log_ && T > car_.segment_start() && car_.Control(T, car_.steer(), car_.speed(), true))
    rec_.Control(T, car_.steer(), car_.speed(), pedals_);
  rep_.sim_start = t0_;
  rep_.sim_end = T;
  rep_.wall_s = Seconds(wall0, Clock::now());
  rep_.final_level = quality_.level();
  rep_.final_scale = quality_.scale();
  rep_.final_projectors = quality_.projectors();
  rep_.final_lod_m = quality_.lod_m();
  const RenderStats& st = views_.view().stats();
  const double n = double(std::max<size_t>(1, rep_.frames));
  rep_.stages = {{"draw_ms", st.draw_ms / n},         {"shade_ms", st.shade_ms / n},
                 {"readback_ms", st.readback_ms / n}, {"fill_ms", st.fill_ms / n},
                 {"cull_ms", st.cull_ms / n},         {"load_ms", views_.view().load_ms() / n}};
  rep_.driving = measures_.Summary();
  if (rep_.ended.empty()) rep_.ended = log_ ? "the end of the log" : "--duration reached";
}

nlohmann::json SummaryJson(const SimulateOptions& o, const SimulateReport& r) {
  SimulateOptions copy = o;
  const OptionTable table = DeclareOptions(copy);
  const DrivingSummary& d = r.driving;
  nlohmann::json q = nlohmann::json::array();
  for (const QualityChange& c : r.quality)
    q.push_back({{"time", c.time},
                 {"level", c.level},
                 {"render_scale", c.render_scale},
                 {"projectors", c.projectors},
                 {"why", c.why}});
  return {{"tool", "simulate"},
          {"version", kVersion},
          {"options", table.Json()},
          {"gl", r.gl},
          {"device", r.device},
          {"ended", r.ended},
          {"simulation", {{"start", r.sim_start}, {"end", r.sim_end}, {"steps", r.steps}}},
          {"frames",
           {{"shown", r.frames},
            {"wall_s", r.wall_s},
            {"fps", r.wall_s > 0 ? double(r.frames) / r.wall_s : 0.0},
            {"render_ms", r.frames ? r.render_ms / double(r.frames) : 0.0}}},
          {"quality",
           {{"changes", q},
            {"final_level", r.final_level},
            {"render_scale", r.final_scale},
            {"projectors", r.final_projectors}}},
          {"driving",
           {{"duration_s", d.duration},
            {"distance_m", d.distance},
            {"mean_speed_kmh", d.mean_speed * 3.6},
            {"sd_speed_kmh", d.sd_speed * 3.6},
            {"speed_limit_kmh", d.speed_limit * 3.6},
            {"rms_over_limit_kmh", d.rms_over_limit * 3.6},
            {"time_over_limit_s", d.time_over},
            {"mean_offset_m", d.mean_offset},
            {"sdlp_m", d.sdlp},
            {"max_offset_m", d.max_offset},
            {"resets", d.resets}}},
          {"log", r.log}};
}

// What the car drives: a workspace (its whole mesh) or a road (ROAD/Graph.txt: roadsplit)
// streamed by its graph. Held by pointer: the track refers to the road.
struct Drivable {
  std::optional<Road> road;
  std::optional<Workspace> workspace;
  Mesh mesh;  // a workspace's
  Track track;
  // The workspace, or the fragment the car starts in.
  Workspace StartWorkspace() const {
    return road ? Workspace(road->fragments()[track.ground->home()].dir) : *workspace;
  }
};

std::unique_ptr<Drivable> OpenDrivable(const SimulateOptions& o) {
  auto d = std::make_unique<Drivable>();
  if (Road::IsRoad(o.workspace)) {
    d->road.emplace(o.workspace);
    d->track = LoadRoadTrack(o, *d->road);
    return d;
  }
  d->workspace.emplace(o.workspace);
  d->workspace->Require("simulate", {WsItem::kSparse, WsItem::kMesh});
  d->mesh = ReadMesh(d->workspace->MeshPath().string());
  if (d->mesh.faces.empty())
    throw Error(d->workspace->MeshPath().string(), 0, "the mesh has no triangles");
  d->track = LoadTrack(o, *d->workspace, d->mesh);
  return d;
}

// The car at the start image (an error naming the mesh when it is off it) and the view's plan
// from there and the recorded views.
void PlanAtStart(const Track& track, LiveView& view, const Workspace& ws) {
  GroundPlacer start_placer(track.Ground(), track.frame, track.car);
  Placement start;
  try {
    start = start_placer.Place(track.rear[track.rec.start], 0);
  } catch (const Error& e) {
    throw Error(ws.MeshPath().string(), 0,
                "the car at the start image " + track.rec.images[track.rec.start]->name +
                    " is off the mesh (" + e.what() + "): choose another --start or " +
                    "--camera-offset");
  }
  view.Plan(start.camera_to_world, track.rec.w2c);
}

}  // namespace

SimulateReport RunSimulate(const SimulateOptions& o, std::ostream& out) {
  o.Check();
  // The small files first: a bad one fails fast, before the workspace is loaded.
  ControlsLog log;
  if (!o.replay.empty()) log = ReadControlsTsv(o.replay);
  const InputMapping mapping = o.mapping.empty() ? InputMapping() : ReadInputMapping(o.mapping);
  std::vector<VirtualRow> script;
  if (!o.virtual_input.empty()) script = ReadVirtualScript(o.virtual_input);
  const std::unique_ptr<Drivable> d = OpenDrivable(o);
  Track& track = d->track;
  const std::optional<Road>& road = d->road;
  const size_t start_home = road ? track.ground->home() : 0;
  const Workspace ws = d->StartWorkspace();
  const Reconstruction& start_rec = road ? track.where->model(start_home) : track.rec.rec;
  SimulateReport rep;
  // SDL and the window first: SDL's offscreen video driver sets up EGL state of its own, so the
  // renderer's context is made after it (and stays the current one).
  std::optional<SdlSession> sdl;
  std::unique_ptr<Screen> screen;
  if (!o.explain) sdl.emplace(!o.no_window);
  if (!o.explain && !o.no_window) {
    const Camera sc = ScreenCamera(track.rec.rec, o.size);
    screen = std::make_unique<Screen>(int(sc.width) * o.screens, int(sc.height),
                                      "mvtm simulate — " + o.workspace);
  }
  auto ctx = GlContext::Create(o.gl);
  rep.gl = ctx->Describe();
  Views views(o, track);
  if (road)
    views.OpenRoad();
  else
    views.Open(ws, start_rec, d->mesh);
  LiveView& view = views.view();
  PlanAtStart(track, view, ws);
  if (o.explain) {
    nlohmann::json j;
    j["screens"] = o.screens;
    j["render_size"] = {view.screen().width, view.screen().height};
    j["gl"] = rep.gl;
    if (road) j["fragment"] = road->fragments()[start_home].id;
    j["effects"] = ExplainEffects(view.survey(), view.plan());
    j["shader_defines"] = view.plan().Defines();
    j["depth_maps"] = DepthSource(ws, start_rec, view.plan());
    out << j.dump(2) << "\n";
    return rep;
  }
  if (const std::string depth = DepthSource(ws, start_rec, view.plan()); !depth.empty())
    rep.log.push_back(road ? depth + " in the start fragment" : depth);
  Devices devices(mapping, script, !o.no_window);
  rep.device = o.replay.empty() ? devices.Describe() : "replay of " + o.replay;
  if (rep.device == "none")
    rep.log.push_back(
        "no input device: the car stands until a wheel or game controller is plugged in (or "
        "open a window for the keyboard)");
  Recorder rec(o.record);
  Session session(o, track, views, devices, screen.get(), rec, o.replay.empty() ? nullptr : &log,
                  rep);
  session.Run();
  rec.Finish(SummaryJson(o, rep));
  if (!o.screenshot.empty()) {
    const Image shot = session.Screenshot();
    if (!shot.empty()) WriteImage(o.screenshot, shot);
  }
  return rep;
}

}  // namespace mvtm
