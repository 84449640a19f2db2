// bakedepth — thin main: the declared option table, then RunBakeDepth().
#include <cstdio>
#include <iostream>

#include "bakedepth.h"
#include "cli/app.h"
#include "cli/options.h"

namespace {

constexpr const char* kAbout =
    "Pre-bake one linear float32 depth map (depth/NAME.exr, +inf = no surface) per "
    "image of a workspace from its mesh, for the PTM occlusion test.";

// Runs the tool and prints its summary; the exit status.
int RunAndReport(mvtm::BakeDepthOptions& o) {
  auto r = mvtm::RunBakeDepth(o);
  if (!o.quiet) {
    std::cerr << "bakedepth: " << r.written << " depth maps written, " << r.skipped
              << " up to date";
    if (!r.why.empty()) std::cerr << " [" << r.why << "]";
    if (r.written)
      std::fprintf(stderr, " (%.1f ms render, %.1f ms write per map; %s)", r.render_ms / r.written,
                   r.write_ms / r.written, r.gl.c_str());
    std::cerr << "\n";
  }
  return 0;
}

}  // namespace

int main(int argc, char** argv) {
  mvtm::BakeDepthOptions o;
  return mvtm::RunTool(mvtm::DeclareOptions(o), kAbout, argc, argv,
                       [&] { return RunAndReport(o); });
}
