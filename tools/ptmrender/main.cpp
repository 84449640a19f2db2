// ptmrender — thin main: option table, then RunPtmRender().
#include <cstdio>
#include <iostream>

#include "cli/app.h"
#include "cli/options.h"
#include "ptmrender.h"
#include "render/context.h"

int main(int argc, char** argv) {
  mvtm::PtmRenderOptions o;
  CLI::App app;
  mvtm::ConfigureApp(
      app, "ptmrender",
      "Render a workspace's mesh textured by projecting its photographs (projective texture "
      "mapping) along any trajectory, headless; only the effects the scene needs are compiled.");
  app.add_option("WS", o.workspace,
                 "Workspace folder (sparse/, images/, mesh.ply; depth/, masks/, textures/ used "
                 "when present)")
      ->required();
  app.add_option("OUTDIR", o.outdir, "Folder for the frames (NAME.png)")->required();
  auto* poses = app.add_option("--poses", o.poses,
                               "Render poses: COLMAP images.txt, TUM or KITTI trajectory");
  auto* at = app.add_flag("--at-images", o.at_images,
                          "Render at the workspace's own image poses (the default)");
  poses->excludes(at);
  app.add_flag("--exclude-self", o.exclude_self,
               "With --at-images: never use an image as a projector for its own pose");
  app.add_option("--lateral", o.lateral,
                 "Move each pose sideways, metres to the left (+) or right (-): a lane change")
      ->capture_default_str();
  app.add_option("--yaw", o.yaw,
                 "Turn each pose, degrees to the left (+) or right (-), about the camera's up axis")
      ->capture_default_str();
  mvtm::AddChoiceOption(app, "--mode", o.mode, mvtm::kPtmModes,
                        "ptm: project photographs; vertex: vertex colours only");
  app.add_option("--projectors", o.projectors, "K: projectors tried per pixel, best first")
      ->capture_default_str()
      ->check(CLI::Range(1, 16));
  app.add_option("--bias", o.bias, "Occlusion bias, relative: occluded when z > depth*(1+B)")
      ->capture_default_str();
  app.add_option("--max-heading", o.selection.max_heading_deg,
                 "Heading gate for projectors, degrees")
      ->capture_default_str();
  app.add_option("--ahead-weight", o.selection.ahead_weight,
                 "Extra cost per metre a projector is ahead of the pose (0 = nearest pose)")
      ->capture_default_str();
  app.add_flag("--no-occlusion", o.no_occlusion,
               "Never test projector depth (off even when needed)");
  app.add_flag("--no-skybox", o.no_skybox, "Constant background instead of projected sky");
  app.add_flag("--no-masks", o.no_masks, "Ignore masks/ (vehicles are projected too)");
  app.add_flag("--no-exposure", o.no_exposure,
               "Ignore exposure.tsv (each projector at its own exposure)");
  app.add_option("--size", o.size, "Render size WxH (default: the camera's)");
  app.add_flag(
      "--explain", o.explain,
      "Print the effects plan as JSON (with the reason for each effect) and render nothing");
  app.add_flag("--provenance", o.provenance,
               "Also write OUTDIR/provenance/NAME.png: which projector coloured each pixel (254 "
               "vertex colour, 255 background)");
  app.add_flag("--exr", o.exr, "Write float EXR frames (0..1) instead of 8-bit PNG");
  mvtm::AddChoiceOption(app, "--gl", o.gl, mvtm::GlBackendNames(), "OpenGL backend");
  mvtm::AddWorkOptions(app, o, "render poses", "in pose order",
                       "Re-render frames that already exist");
  return mvtm::RunMain(app, "ptmrender", argc, argv, [&] {
    auto r = mvtm::RunPtmRender(o, std::cout);
    if (!o.quiet && !o.explain) {
      std::fprintf(stderr, "ptmrender: %zu frames rendered, %zu up to date", r.rendered, r.skipped);
      if (r.rendered)
        std::fprintf(stderr, " (%.1f ms render, %.1f ms depth, %.1f ms load per frame; %s)",
                     r.render_ms / r.rendered, r.depth_ms / r.rendered, r.load_ms / r.rendered,
                     r.gl.c_str());
      std::fprintf(stderr, "\n");
    }
    return 0;
  });
}
