// bakedepth — thin main: option table, then RunBakeDepth().
#include <cstdio>
#include <iostream>

#include "bakedepth.h"
#include "cli/app.h"
#include "cli/options.h"
#include "render/context.h"

int main(int argc, char** argv) {
  mvtm::BakeDepthOptions o;
  CLI::App app;
  mvtm::ConfigureApp(
      app, "bakedepth",
      "Pre-bake one linear float32 depth map (depth/NAME.exr, +inf = no surface) per "
      "image of a workspace from its mesh, for the PTM occlusion test.");
  app.add_option("WS", o.workspace, "Workspace folder (sparse/, mesh.ply)")->required();
  app.add_option("--scale", o.scale, "Depth map size relative to the image (0 < F <= 4)")
      ->capture_default_str();
  mvtm::AddWorkOptions(app, o, "images", "in name order",
                       "Rebake maps that are newer than the mesh and model");
  mvtm::AddChoiceOption(app, "--gl", o.gl, mvtm::GlBackendNames(), "OpenGL backend");
  return mvtm::RunMain(app, "bakedepth", argc, argv, [&] {
    auto r = mvtm::RunBakeDepth(o);
    if (!o.quiet) {
      std::cerr << "bakedepth: " << r.written << " depth maps written, " << r.skipped
                << " up to date";
      if (r.written)
        std::fprintf(stderr, " (%.1f ms render, %.1f ms write per map; %s)",
                     r.render_ms / r.written, r.write_ms / r.written, r.gl.c_str());
      std::cerr << "\n";
    }
    return 0;
  });
}
