// orb2colmap — thin main: the declared option table, then RunOrb2Colmap().
#include <cmath>
#include <cstdio>
#include <iostream>

#include "cli/app.h"
#include "cli/options.h"
#include "orb2colmap.h"

namespace {

constexpr const char* kAbout =
    "Convert ORB-SLAM2 keyframe or ground-truth poses (TUM or KITTI, camera-to-world) "
    "into a COLMAP model of every frame, interpolating between keyframes.";

// Runs the tool and prints its summary; the exit status.
int RunAndReport(mvtm::Orb2ColmapOptions& o) {
  auto r = mvtm::RunOrb2Colmap(o);
  if (r.up_to_date) {
    if (!o.quiet)
      std::cerr << "orb2colmap: " << o.outdir << " is up to date (use --force to rewrite)\n";
    return 0;
  }
  if (!o.quiet) {
    if (o.trajectory == mvtm::kNoTrajectory)
      std::cerr << "orb2colmap: the camera and " << r.written << " images without poses written to "
                << o.database;
    else
      std::cerr << "orb2colmap: " << r.written << " frames written from " << r.keyframes
                << " poses";
    if (r.dropped) std::cerr << "; " << r.dropped << " outside the pose time span dropped";
    if (r.clamped) std::cerr << "; " << r.clamped << " outside the pose time span clamped";
    if (r.reordered) std::cerr << "; " << r.reordered << " poses were out of time order (sorted)";
    if (r.from_cam != r.to_cam) {
      // The centre of camera N in camera M's frame is −offset (+ 0.0: no "-0.0000").
      auto mm = [](double v) { return std::round(-v * 1e4) / 1e4 + 0.0; };
      char buf[160];
      std::snprintf(buf, sizeof buf,
                    "; the poses of camera P%d moved to P%d: (%.4f, %.4f, %.4f) m from it (x "
                    "right, y down, z forward)",
                    r.from_cam, r.to_cam, mm(r.offset.x()), mm(r.offset.y()), mm(r.offset.z()));
      std::cerr << buf;
    }
    if (!r.why.empty()) std::cerr << " [" << r.why << "]";
    std::cerr << "\n";
  }
  return 0;
}

}  // namespace

int main(int argc, char** argv) {
  mvtm::Orb2ColmapOptions o;
  return mvtm::RunTool(mvtm::DeclareOptions(o), kAbout, argc, argv,
                       [&] { return RunAndReport(o); });
}
