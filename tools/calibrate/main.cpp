// calibrate — thin main: the declared option table, then RunCalibrate().
#include <cstdio>

#include "calibrate.h"
#include "cli/app.h"
#include "cli/options.h"

namespace {

constexpr const char* kAbout =
    "A camera's intrinsics from views of a chessboard (a folder of photos or a video segment): "
    "a COLMAP camera for the road build, its spec printed for orb2colmap --camera.";

int RunAndReport(mvtm::CalibrateOptions& o) {
  const auto r = mvtm::RunCalibrate(o);
  std::printf("%s\n", r.spec.c_str());  // the result is data: printed with -q too
  if (o.quiet) return 0;
  if (r.up_to_date)
    std::fprintf(stderr, "calibrate: %s is up to date (--force rewrites)\n", o.outdir.c_str());
  else
    std::fprintf(stderr,
                 "calibrate: board found in %zu of %zu views, %zu used, %zu dropped as outliers; "
                 "RMS reprojection error %.3f px%s\n",
                 r.found, r.views, r.used, r.dropped, r.rms,
                 r.why.empty() ? "" : (" [" + r.why + "]").c_str());
  return 0;
}

}  // namespace

int main(int argc, char** argv) {
  mvtm::CalibrateOptions o;
  return mvtm::RunTool(mvtm::DeclareOptions(o), kAbout, argc, argv,
                       [&] { return RunAndReport(o); });
}
