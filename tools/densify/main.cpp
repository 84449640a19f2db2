// densify — thin main: option table, then RunDensify().
#include <cstdio>
#include <iostream>

#include "cli/app.h"
#include "cli/options.h"
#include "densify.h"

int main(int argc, char** argv) {
  mvtm::DensifyOptions o;
  CLI::App app;
  mvtm::ConfigureApp(
      app, "densify",
      "Dense depth and confidence per image of a workspace (stereo/NAME.exr, stereo/NAME.conf.exr) "
      "by "
      "multi-view plane-sweep stereo on the CPU: ground, facade and fronto-parallel sweeps.");
  app.add_option("WS", o.workspace, "Workspace folder (sparse/ with points, images/)")->required();
  app.add_option("--scale", o.scale, "Depth map size relative to the image (0 < F <= 1)")
      ->capture_default_str();
  app.add_option("--planes", o.planes, "Planes per sweep direction (2..512)")
      ->capture_default_str();
  app.add_flag("--no-ground", o.no_ground, "Leave out the ground-parallel sweep");
  app.add_flag("--no-facade", o.no_facade, "Leave out the facade-parallel sweep");
  app.add_flag("--no-fronto", o.no_fronto, "Leave out the fronto-parallel sweep");
  app.add_option("--neighbours", o.neighbours.count, "Neighbour images per reference (1..16)")
      ->capture_default_str();
  app.add_option("--min-baseline", o.neighbours.min_baseline,
                 "Smallest baseline, as a fraction of the median camera spacing")
      ->capture_default_str();
  app.add_option("--max-angle", o.neighbours.max_angle_deg,
                 "Largest angle between viewing directions, degrees")
      ->capture_default_str();
  app.add_option("--min-coverage", o.neighbours.min_coverage,
                 "Share of the reference's sparse points a neighbour must see")
      ->capture_default_str();
  app.add_option("--window", o.sweep.window, "ZNCC window side in pixels (odd, 3..31)")
      ->capture_default_str();
  app.add_option("--best-k", o.sweep.best_k, "Neighbours aggregated per pixel: the best K of N")
      ->capture_default_str();
  app.add_option("--min-score", o.sweep.min_score,
                 "Aggregated ZNCC below which a pixel gets no depth")
      ->capture_default_str();
  app.add_option("--min-margin", o.sweep.min_margin,
                 "Best score minus the mean over planes below which a match is ambiguous")
      ->capture_default_str();
  app.add_option("--refine", o.sweep.refine,
                 "Sub-steps per plane spacing of the per-pixel refinement of the best plane "
                 "(0..64; 0: a parabola through the planes only)")
      ->capture_default_str();
  app.add_option("--min-texture", o.sweep.min_texture,
                 "Grey standard deviation (0..255) below which a window is textureless")
      ->capture_default_str();
  mvtm::AddWorkOptions(app, o, "images", "in name order",
                       "Recompute maps that are newer than the model");
  return mvtm::RunMain(app, "densify", argc, argv, [&] {
    auto r = mvtm::RunDensify(o);
    if (!o.quiet) {
      std::fprintf(stderr, "densify: %zu depth maps written, %zu up to date", r.written, r.skipped);
      if (r.written)
        std::fprintf(stderr, " (%.0f ms per image, %.1f %% of pixels with a depth)", r.ms_per_image,
                     100 * r.valid_share);
      if (r.no_neighbours)
        std::fprintf(stderr, "; %zu images had no usable neighbour (+inf maps)", r.no_neighbours);
      std::fprintf(stderr, "\n");
    }
    return 0;
  });
}
