// inpaint3d — thin main: the declared option table, then RunInpaint3d().
#include <cstdio>

#include "cli/app.h"
#include "cli/options.h"
#include "inpaint3d.h"

namespace {

constexpr const char* kAbout =
    "Remove masked vehicles from a workspace's images: re-render the pixels under each mask from "
    "partner images through the mesh (or inpaint them in 2-D), writing textures/ and a "
    "provenance image.";

// Runs the tool and prints its summary; the exit status.
int RunAndReport(mvtm::Inpaint3dOptions& o) {
  auto r = mvtm::RunInpaint3d(o);
  if (!o.quiet) {
    std::fprintf(stderr,
                 "inpaint3d: %zu images: %zu inpainted, %zu copied (no mask), %zu up to date",
                 r.images, r.inpainted, r.copied, r.skipped);
    if (!r.why.empty()) std::fprintf(stderr, " [%s]", r.why.c_str());
    if (r.masked_pixels)
      std::fprintf(stderr,
                   "; %zu masked pixels: %zu partners, %zu sky, %zu vertex colour, %zu "
                   "background, %zu 2-D",
                   r.masked_pixels, r.from_partners, r.from_sky, r.from_vertex, r.from_background,
                   r.from_2d);
    std::fprintf(stderr, "\n");
  }
  return 0;
}

}  // namespace

int main(int argc, char** argv) {
  mvtm::Inpaint3dOptions o;
  return mvtm::RunTool(mvtm::DeclareOptions(o), kAbout, argc, argv,
                       [&] { return RunAndReport(o); });
}
