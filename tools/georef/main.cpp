// georef — thin main: the declared option table, then RunGeoref().
#include <cstdio>

#include "cli/app.h"
#include "cli/options.h"
#include "georef.h"

namespace {

constexpr const char* kAbout =
    "Make a structure-from-motion model upright and metric: up from the road under the "
    "cameras (z up, x the first camera's heading, origin below it), metres from the camera's "
    "height above the road, or placed in UTM by a GPS log (GPX or NMEA); optionally score it "
    "against a reference trajectory.";

void PrintSummary(const mvtm::GeorefOptions& o, const mvtm::GeorefReport& r) {
  if (r.up_to_date)
    std::fprintf(stderr, "georef: %s is up to date (--force rewrites)\n", o.outdir.c_str());
  else
    std::fprintf(stderr,
                 "georef: ground under %zu of %zu cameras (%zu points); camera height %.6g model "
                 "units (spread %.2g), scale %.6g; road up %.2f deg from the cameras' up%s\n",
                 r.cameras_with_ground, r.cameras, r.ground_points, r.camera_height,
                 r.height_spread, r.scale, r.tilt_degrees,
                 r.why.empty() ? "" : (" [" + r.why + "]").c_str());
  if (r.gps)
    std::fprintf(
        stderr,
        "georef: GPS: %zu of %zu frames within the log, %zu fixes among them, %zu inliers, "
        "%.3g m RMS; offset %.2f s; UTM "
        "zone %s; scale %.6g m per model unit from GPS alone (+- %.2g), %s used\n",
        r.gps_matched, r.gps_frames, r.gps_pairs, r.gps_inliers, r.gps_rms, r.gps_offset,
        r.utm_zone.c_str(), r.scale_gps, r.scale_gps_sigma, r.scale_source.c_str());
  if (r.gps_bad_checksums > 0)
    std::fprintf(stderr, "georef: warning: %zu NMEA sentences with a wrong checksum skipped\n",
                 r.gps_bad_checksums);
}

int RunAndReport(mvtm::GeorefOptions& o) {
  const auto r = mvtm::RunGeoref(o);
  if (!o.quiet) PrintSummary(o, r);
  // The comparison is data (stdout), printed with -q too; -q silences only the summary.
  if (!o.compare.empty())
    std::printf(
        "compare\tmatched %zu\tpath %.4f\tate_rmse %.6f\tate_percent %.4f\treference_scale "
        "%.6f\n",
        r.matched, r.path_length, r.ate_rmse,
        r.path_length > 0 ? 100 * r.ate_rmse / r.path_length : 0.0, r.reference_scale);
  return 0;
}

}  // namespace

int main(int argc, char** argv) {
  mvtm::GeorefOptions o;
  return mvtm::RunTool(mvtm::DeclareOptions(o), kAbout, argc, argv,
                       [&] { return RunAndReport(o); });
}
