// boresight — thin main: the declared option table, then RunBoresight().
#include <cstdio>

#include "boresight.h"
#include "cli/app.h"
#include "cli/options.h"

namespace {

constexpr const char* kAbout =
    "Fit the camera's boresight to a model whose poses are of record (GPS/INS, SLAM, ground "
    "truth): the one rotation shared by every image that makes the feature tracks agree best, "
    "the camera centres kept as recorded; write the model turned by it.";

void PrintSummary(const mvtm::BoresightToolOptions& o, const mvtm::BoresightReport& r) {
  if (r.up_to_date) {
    std::fprintf(stderr, "boresight: %s is up to date (--force rewrites)\n", o.outdir.c_str());
    return;
  }
  const auto& f = r.fit;
  const double deg = 180 / 3.14159265358979323846;
  std::fprintf(stderr,
               "boresight: pitch %+.4f yaw %+.4f roll %+.4f deg (+- %.2g; %zu of 3 directions "
               "left as recorded) from %zu points, %zu observations in %zu images (%zu "
               "excluded, %zu outliers); reprojection error median %.3f -> %.3f px, mean %.3f "
               "-> %.3f px; %s%s\n",
               f.rotation.x() * deg, f.rotation.y() * deg, f.rotation.z() * deg, f.sigma_deg,
               f.frozen.size(), f.points, f.observations, f.images, r.excluded, f.outliers,
               f.median_before, f.median_after, f.mean_before, f.mean_after,
               f.applied ? "the model turned by it"
                         : "under --min-gain of the error: the model written as recorded",
               r.why.empty() ? "" : (" [" + r.why + "]").c_str());
}

}  // namespace

int main(int argc, char** argv) {
  mvtm::BoresightToolOptions o;
  return mvtm::RunTool(mvtm::DeclareOptions(o), kAbout, argc, argv, [&] {
    const auto r = mvtm::RunBoresight(o);
    if (!o.quiet) PrintSummary(o, r);
    return 0;
  });
}
