// exposure — thin main: the declared option table, then RunExposure().
#include <cstdio>

#include "cli/app.h"
#include "cli/options.h"
#include "exposure_tool.h"

namespace {

constexpr const char* kAbout =
    "Fit a gain and an offset per image of a workspace (I = gain * L + offset) to the sparse "
    "points the images share, and write WS/exposure.tsv: ptmrender then blends its projectors "
    "at one common exposure.";

// Runs the tool and prints its summary; the exit status.
int RunAndReport(mvtm::ExposureToolOptions& o) {
  const auto r = mvtm::RunExposure(o);
  if (o.quiet) return 0;
  if (r.up_to_date)
    std::fprintf(stderr, "exposure: %s/exposure.tsv is up to date (--force refits)\n",
                 o.workspace.c_str());
  else
    std::fprintf(
        stderr,
        "exposure: %zu of %zu images fitted from %zu observations; gain %.3f..%.3f, offset "
        "%.1f..%.1f%s\n",
        r.fitted, r.images, r.observations, r.gain_min, r.gain_max, r.offset_min, r.offset_max,
        r.why.empty() ? "" : (" [" + r.why + "]").c_str());
  return 0;
}

}  // namespace

int main(int argc, char** argv) {
  mvtm::ExposureToolOptions o;
  return mvtm::RunTool(mvtm::DeclareOptions(o), kAbout, argc, argv,
                       [&] { return RunAndReport(o); });
}
