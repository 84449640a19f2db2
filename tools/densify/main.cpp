// densify — thin main: the declared option table, then RunDensify().
#include <cstdio>
#include <iostream>

#include "cli/app.h"
#include "cli/options.h"
#include "densify.h"

namespace {

constexpr const char* kAbout =
    "Dense depth and confidence per image of a workspace (stereo/NAME.exr, stereo/NAME.conf.exr) "
    "by "
    "multi-view plane-sweep stereo on the CPU: ground, facade and fronto-parallel sweeps.";

// Runs the tool and prints its summary; the exit status.
int RunAndReport(mvtm::DensifyOptions& o) {
  auto r = mvtm::RunDensify(o);
  if (!o.quiet) {
    std::fprintf(stderr, "densify: %zu depth maps written, %zu up to date", r.written, r.skipped);
    if (!r.why.empty()) std::fprintf(stderr, " [%s]", r.why.c_str());
    if (r.written)
      std::fprintf(stderr, " (%.0f ms per image, %.1f %% of pixels with a depth)", r.ms_per_image,
                   100 * r.valid_share);
    if (r.no_neighbours)
      std::fprintf(stderr, "; %zu images had no usable neighbour (+inf maps)", r.no_neighbours);
    std::fprintf(stderr, "\n");
  }
  return 0;
}

}  // namespace

int main(int argc, char** argv) {
  mvtm::DensifyOptions o;
  return mvtm::RunTool(mvtm::DeclareOptions(o), kAbout, argc, argv,
                       [&] { return RunAndReport(o); });
}
