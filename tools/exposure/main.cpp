// exposure — thin main: option table, then RunExposure().
#include <cstdio>

#include "cli/app.h"
#include "cli/options.h"
#include "exposure_tool.h"

int main(int argc, char** argv) {
  mvtm::ExposureToolOptions o;
  bool offsets = false;
  CLI::App app;
  mvtm::ConfigureApp(
      app, "exposure",
      "Fit a gain and an offset per image of a workspace (I = gain * L + offset) to the sparse "
      "points the images share, and write WS/exposure.tsv: ptmrender then blends its projectors "
      "at one common exposure.");
  app.add_option("WS", o.workspace, "Workspace folder (sparse/ with points, images/)")->required();
  app.add_flag("--offsets", offsets,
               "Fit offsets as well as gains (black-level changes; less robust to noisy samples)");
  app.add_option("--iterations", o.fit.iterations, "Alternating least-squares rounds (1..1000)")
      ->capture_default_str();
  app.add_option(
         "--outlier-mads", o.fit.outlier_mads,
         "Observations further than this many median absolute deviations from the fit are dropped")
      ->capture_default_str();
  app.add_option("--min-points", o.fit.min_points,
                 "Observations an image needs to be fitted (else identity)")
      ->capture_default_str();
  app.add_flag("--force", o.force, "Refit when exposure.tsv is newer than the model");
  mvtm::AddQuietOption(app, o.quiet);
  return mvtm::RunMain(app, "exposure", argc, argv, [&] {
    o.fit.offsets = offsets;
    const auto r = mvtm::RunExposure(o);
    if (o.quiet) return 0;
    if (r.up_to_date)
      std::fprintf(stderr, "exposure: %s/exposure.tsv is up to date (--force refits)\n",
                   o.workspace.c_str());
    else
      std::fprintf(
          stderr,
          "exposure: %zu of %zu images fitted from %zu observations; gain %.3f..%.3f, offset "
          "%.1f..%.1f\n",
          r.fitted, r.images, r.observations, r.gain_min, r.gain_max, r.offset_min, r.offset_max);
    return 0;
  });
}
