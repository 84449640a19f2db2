// inpaint3d — thin main: option table, then RunInpaint3d().
#include <cstdio>

#include "cli/app.h"
#include "cli/options.h"
#include "inpaint3d.h"
#include "render/context.h"

int main(int argc, char** argv) {
  mvtm::Inpaint3dOptions o;
  CLI::App app;
  mvtm::ConfigureApp(
      app, "inpaint3d",
      "Remove masked vehicles from a workspace's images: re-render the pixels under each mask from "
      "partner images through the mesh (or inpaint them in 2-D), writing textures/ and a "
      "provenance image.");
  app.add_option("WS", o.workspace,
                 "Workspace folder (sparse/, images/, masks/, partners.tsv, mesh.ply; depth/ used "
                 "when present)")
      ->required();
  mvtm::AddChoiceOption(
      app, "--method", o.method, mvtm::kInpaintMethods,
      "3d: partners through the mesh; telea, ns: OpenCV inpainting; patch2d: thesis 5.2 "
      "templates");
  app.add_option("--partners", o.partners,
                 "N: partners used per image (ranks 1..N of partners.tsv)")
      ->check(CLI::Range(1, 16))
      ->capture_default_str();
  app.add_option("--dilate", o.dilate, "Pixels the mask is dilated by before inpainting")
      ->check(CLI::Range(0, 64))
      ->capture_default_str();
  app.add_option("--radius", o.radius, "telea, ns: inpainting radius in pixels")
      ->capture_default_str();
  app.add_option("--bias", o.bias, "3d: occlusion bias, relative: occluded when z > depth*(1+B)")
      ->capture_default_str();
  mvtm::AddChoiceOption(app, "--gl", o.gl, mvtm::GlBackendNames(), "3d: OpenGL backend");
  mvtm::AddWorkOptions(app, o, "images", "in name order", "Rewrite outputs that are up to date");
  return mvtm::RunMain(app, "inpaint3d", argc, argv, [&] {
    auto r = mvtm::RunInpaint3d(o);
    if (!o.quiet) {
      std::fprintf(stderr,
                   "inpaint3d: %zu images: %zu inpainted, %zu copied (no mask), %zu up to date",
                   r.images, r.inpainted, r.copied, r.skipped);
      if (r.masked_pixels)
        std::fprintf(stderr,
                     "; %zu masked pixels: %zu partners, %zu sky, %zu vertex colour, %zu "
                     "background, %zu 2-D",
                     r.masked_pixels, r.from_partners, r.from_sky, r.from_vertex, r.from_background,
                     r.from_2d);
      std::fprintf(stderr, "\n");
    }
    return 0;
  });
}
