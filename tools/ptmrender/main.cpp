// ptmrender — thin main: the declared option table, then RunPtmRender().
#include <cstdio>
#include <iostream>

#include "cli/app.h"
#include "cli/options.h"
#include "ptmrender.h"

namespace {

constexpr const char* kAbout =
    "Render a workspace's mesh textured by projecting its photographs (projective texture "
    "mapping) along any trajectory, headless; only the effects the scene needs are compiled.";

// Runs the tool and prints its summary; the exit status.
int RunAndReport(mvtm::PtmRenderOptions& o) {
  auto r = mvtm::RunPtmRender(o, std::cout);
  if (!o.quiet && !o.explain) {
    std::fprintf(stderr, "ptmrender: %zu frames rendered, %zu up to date", r.rendered, r.skipped);
    if (!r.why.empty()) std::fprintf(stderr, " [%s]", r.why.c_str());
    if (r.rendered)
      std::fprintf(stderr, " (%.1f ms render, %.1f ms depth, %.1f ms load per frame; %s)",
                   r.render_ms / r.rendered, r.depth_ms / r.rendered, r.load_ms / r.rendered,
                   r.gl.c_str());
    std::fprintf(stderr, "\n");
  }
  return 0;
}

}  // namespace

int main(int argc, char** argv) {
  mvtm::PtmRenderOptions o;
  return mvtm::RunTool(mvtm::DeclareOptions(o), kAbout, argc, argv,
                       [&] { return RunAndReport(o); });
}
