// drive — thin main: option table, then RunDrive().
#include <cstdio>

#include "cli/app.h"
#include "cli/options.h"
#include "drive.h"

int main(int argc, char** argv) {
  mvtm::DriveOptions o;
  CLI::App app;
  mvtm::ConfigureApp(
      app, "drive",
      "Drive a car on a workspace's mesh and write the camera's poses for ptmrender --poses: a "
      "controls log (time, steering-wheel angle, speed) through the kinematic bicycle model as "
      "exact arcs, or with --lane-change the recorded path moved sideways by a smooth lane "
      "change. The ground height, pitch and roll come from the mesh under the wheels.");
  app.add_option("WS", o.workspace, "Workspace folder (sparse/, mesh.ply)")->required();
  app.add_option("CONTROLS", o.controls,
                 "Controls log: a header naming 'time steer speed' (s, steering-wheel degrees, "
                 "m/s), then one row per sample; omitted with --lane-change");
  app.add_option("OUT", o.out, "Output trajectory file (tum, kitti) or folder (colmap)");
  app.add_option("--lane-change", o.lane_change,
                 "T0:DURATION:OFFSET: drive the recorded path instead of CONTROLS, moving OFFSET "
                 "metres to the left (+) or right (-) from T0 seconds for DURATION seconds");
  app.add_option("--scale", o.scale, "Model units per metre (1 for a metric workspace)");
  app.add_flag("--metric", o.metric, "The workspace is in metres (--scale 1)");
  app.add_option("--wheelbase", o.wheelbase, "Rear to front axle, metres")->capture_default_str();
  app.add_option("--steering-ratio", o.steering_ratio, "Steering-wheel angle per road-wheel angle")
      ->capture_default_str();
  app.add_option("--max-steer", o.max_steer,
                 "Largest road-wheel angle, degrees; larger ones are clamped (and counted)")
      ->capture_default_str();
  app.add_option("--track", o.track, "Left to right wheel, metres (where the ground is probed)")
      ->capture_default_str();
  app.add_option("--camera-offset", o.camera_offset,
                 "X,Y,Z: the camera in metres forward, left and up of the ground under the rear "
                 "axle centre (default 0,0,H: H the recorded cameras' median height above the "
                 "mesh)");
  app.add_option("--start", o.start,
                 "Start at this workspace image's pose (default: the first, in name order)");
  app.add_option("--pass", o.pass,
                 "The recorded images are those whose names start with this (one drive of the "
                 "road; default: all)");
  app.add_option("--frame-rate", o.frame_rate,
                 "--lane-change: recorded images per second (image k is at k/HZ seconds)")
      ->capture_default_str();
  app.add_option("--rate", o.rate, "Output poses per second")->capture_default_str();
  mvtm::AddChoiceOption(app, "--format", o.format, mvtm::kDriveFormats,
                        "tum: TUM file; kitti: KITTI poses file; colmap: a COLMAP text model "
                        "folder (OUT/images.txt)");
  app.add_flag("--force", o.force, "Rewrite OUT when it is newer than its inputs");
  mvtm::AddQuietOption(app, o.quiet);
  return mvtm::RunMain(app, "drive", argc, argv, [&] {
    if (!o.lane_change.empty() && o.out.empty()) std::swap(o.controls, o.out);  // WS OUT
    const auto r = mvtm::RunDrive(o);
    if (o.quiet) return 0;
    if (!r.ignored_columns.empty()) {
      std::string cols;
      for (const auto& c : r.ignored_columns) cols += (cols.empty() ? "" : " ") + c;
      std::fprintf(stderr, "drive: note: %s: columns not used: %s\n", o.controls.c_str(),
                   cols.c_str());
    }
    if (r.up_to_date) {
      std::fprintf(stderr, "drive: %s is up to date (--force rewrites)\n", r.output.c_str());
      return 0;
    }
    if (r.clamped)
      std::fprintf(stderr, "drive: note: %zu samples steer beyond --max-steer %g: clamped\n",
                   r.clamped, o.max_steer);
    char length[32] = "";
    if (r.length > 0) std::snprintf(length, sizeof length, " (%.1f m)", r.length);
    std::fprintf(stderr,
                 "drive: %zu poses over %.3f s%s to %s; scale %g (%s); camera %.3f m "
                 "above the ground%s; max pitch %.2f deg, roll %.2f deg\n",
                 r.poses, r.duration, length, r.output.c_str(), r.scale, r.scale_source.c_str(),
                 r.camera_height, r.height_from_workspace ? " (recorded)" : "", r.max_pitch_deg,
                 r.max_roll_deg);
    return 0;
  });
}
