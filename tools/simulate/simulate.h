// simulate — drive a workspace's road live: a window (SDL2) showing ptmrender's projective
// texture mapping at the car's camera, the car driven by a wheel and pedals, a game controller
// or the keyboard (devices.h), a fixed-step vehicle simulation (drive's kinematic bicycle on the
// mesh, drive/ground.h, plus longitudinal dynamics, drive/vehicle.h) independent of the frame
// rate, adaptive quality to hold a target frame rate, recording and replay. Thesis Ch. 4.2.3,
// App. D.4–D.5, Ch. 6.1–6.2.
//
// Time. Simulation time starts at 0 (--replay: the log's first time). Steps are 1/--sim-rate
// apart on the grid t0 + k/rate (--replay: the log's own sample times, so the path is drive's
// on that log, bit for bit). Controls hold over a step (piecewise constant), the car moves on
// the exact arcs of drive/bicycle.h, and each step's controls are appended to the path only
// when they change (the recorded controls.tsv is exactly those samples). Frames show the pose at
// their simulation time: in real time, the wall clock since the start; with --as-fast, the grid
// t0 + k/--fps (SampleTimes: the last frame at the session's end time), so `drive --rate FPS` on
// the recorded or replayed log gives the same poses at the same times. Steps are never skipped
// under load: every step up to a frame's time is simulated before it is rendered; only frames
// are dropped. Input is read once per step from SDL's device state, pumped once per frame: the
// latency from input to display is at most one frame.
//
// Rendering: ptmrender's renderer, shaders and effects plan (render/effects_plan.h), planned
// from a survey of the start view and of recorded views along the drive, upgraded live when a
// frame shows a hole (skybox, fill; logged); projectors chosen per frame as ptmrender chooses
// them (index/view_selection.h) and read ahead on a background thread for where the car will be
// in half a second (ProjectorSources::Prefetch). Adaptive quality (unless --no-adapt): levels of
// (render scale, projectors, mesh detail) from (1, K, full) down to (0.5, 1, simplified beyond
// 6 m): (1,K) (1,2) (1,2,40 m) (0.75,2,40 m) (0.75,1,25 m) (0.5,1,25 m) (0.5,1,12 m)
// (0.5,1,6 m), the mesh beyond the distance D drawn simplified by vertex clustering on cells of
// D/25, doubling with each doubling of the distance (Renderer::SetDetail); a level down when the
// mean frame time exceeds 90 % of the budget
// 1/--fps (after 10 frames at a level, 3 when over twice the budget), a level up when it is
// under 45 % of it (after 60); never
// below half the window's resolution or one projector. Each change is logged with its reason.
//
// Off the road: no surface under a wheel, or (with --max-offset) farther than that from the
// recorded path, is handled by --off-road: reset (the car put back at the nearest recorded pose,
// standing) or stop (the car stands where it last was on the road). Past the recorded path's
// end: --at-end stop ends the session, loop puts the car back at the start image.
//
// Recording (--record OUT): OUT/controls.tsv (drive's format: time steer speed, then throttle
// brake; a reset is a '# reset' comment: drive skips it and drives on from where the car was,
// so drive reproduces a session only up to its first reset),
// OUT/poses.tsv (a '#' header, then per frame shown: the simulation time, tx ty tz qx qy qz qw of
// the camera-to-world pose (TUM), the display time in wall seconds since the start), the same
// rows as a plain TUM file OUT/poses.tum (for ptmrender --poses and gazemap), OUT/summary.json
// (the driving measures, frame rate, quality changes, options), and with --record-frames the
// frames shown (OUT/frames/NNNNNN.png, without the HUD). Files are written as the session goes
// under OUT/.NAME.partial and renamed when it ends; a killed session leaves only those.
#pragma once

#include <iosfwd>
#include <map>
#include <string>
#include <utility>
#include <vector>

#include "drive/vehicle.h"
#include "render/context.h"
#include "run/option_table.h"

namespace mvtm {

enum class OffRoad { kReset, kStop };
inline const std::vector<std::pair<OffRoad, std::string>> kOffRoads = {{OffRoad::kReset, "reset"},
                                                                       {OffRoad::kStop, "stop"}};
enum class AtEnd { kStop, kLoop };
inline const std::vector<std::pair<AtEnd, std::string>> kAtEnds = {{AtEnd::kStop, "stop"},
                                                                   {AtEnd::kLoop, "loop"}};

struct SimulateOptions {
  std::string workspace;
  std::string size;       // WxH of one screen; default: the camera's
  int screens = 1;        // screens side by side, each its own camera yaw
  double screen_yaw = 0;  // degrees between screens; 0: the camera's horizontal field of view
  double scale = 0;       // model units per metre; 0: not given
  bool metric = false;
  double wheelbase = 2.7, steering_ratio = 15, max_steer = 35, track = 1.6;
  std::string camera_offset, start, pass;
  LongitudinalParams car;  // --max-accel, --max-brake, --drag (m/s², 1/m)
  double max_speed = 180;  // km/h
  double sim_rate = 200;   // simulation steps per second
  double fps = 30;         // target frame rate
  bool no_adapt = false;
  int quality = 0;  // the starting quality level (0: full)
  int projectors = 4;
  double bias = 0.005;
  bool no_occlusion = false, no_skybox = false, no_masks = false, no_exposure = false;
  bool no_blend = false, no_fill = false;
  bool no_seen = false;      // never take what the projectors saw in front of the mesh (stereo/)
  double sky_distance = -1;  // skybox distance, model units (< 0: the scene's far end, 0: infinity)
  std::string record;        // OUT folder
  bool record_frames = false;
  std::string replay;  // controls log
  bool as_fast = false;
  double duration = 0;  // seconds of simulation; 0: until quit or the log's end (the first)
  std::string virtual_input, mapping;
  double speed_limit = 0;  // km/h, 0: none
  OffRoad off_road = OffRoad::kReset;
  AtEnd at_end = AtEnd::kStop;
  double max_offset = 0;   // metres from the recorded path; 0: only the mesh's edge
  std::string screenshot;  // PNG of the last frame shown, as the window showed it
  bool no_hud = false, no_window = false, explain = false;
  GlBackend gl = GlBackend::kAuto;
  bool quiet = false;

  void Check() const;
};

OptionTable DeclareOptions(SimulateOptions& o);

struct QualityChange {
  double time = 0;  // simulation time
  int level = 0;
  double render_scale = 1;
  int projectors = 1;
  double lod_m = 0;  // level-of-detail distance, metres (0: full detail)
  std::string why;
};

struct SimulateReport {
  std::string gl, device;
  size_t frames = 0, steps = 0;
  double wall_s = 0;     // the loop's wall time
  double render_ms = 0;  // mean per frame (all screens)
  double frame_ms = 0;   // mean wall time per frame
  double sim_start = 0, sim_end = 0;
  int final_level = 0;
  double final_scale = 1;
  int final_projectors = 1;
  double final_lod_m = 0;
  std::map<std::string, double> stages;  // mean per frame: draw_ms, shade_ms, ..., triangles
  std::vector<QualityChange> quality;
  std::vector<std::string> log;  // devices, plan upgrades, resets
  DrivingSummary driving;
  bool quit = false;  // ended by the user (window closed, Escape, a signal)
  std::string ended;  // why the session ended
};

// Runs a session (or with explain, prints the plan to `out`). Throws Error / UsageError.
SimulateReport RunSimulate(const SimulateOptions& options, std::ostream& out);

}  // namespace mvtm
