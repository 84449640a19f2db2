// drive — thin main: the declared option table, then RunDrive().
#include <cstdio>
#include <string>
#include <utility>

#include "cli/app.h"
#include "cli/options.h"
#include "drive.h"

namespace {

constexpr const char* kAbout =
    "Drive a car on a workspace's mesh and write the camera's poses for ptmrender --poses: a "
    "controls log (time, steering-wheel angle, speed) through the kinematic bicycle model as "
    "exact arcs, or with --lane-change the recorded path moved sideways by a smooth lane "
    "change. The ground height, pitch and roll come from the mesh under the wheels.";

// Runs the tool and prints its summary; the exit status.
int RunAndReport(mvtm::DriveOptions& o) {
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
               "above the ground%s; max pitch %.2f deg, roll %.2f deg",
               r.poses, r.duration, length, r.output.c_str(), r.scale, r.scale_source.c_str(),
               r.camera_height, r.height_from_workspace ? " (recorded)" : "", r.max_pitch_deg,
               r.max_roll_deg);
  if (r.fragments) std::fprintf(stderr, "; %zu fragments of the road entered", r.fragments);
  if (!r.why.empty()) std::fprintf(stderr, " [%s]", r.why.c_str());
  std::fprintf(stderr, "\n");
  return 0;
}

}  // namespace

int main(int argc, char** argv) {
  mvtm::DriveOptions o;
  return mvtm::RunTool(mvtm::DeclareOptions(o), kAbout, argc, argv,
                       [&] { return RunAndReport(o); });
}
