// roadmesh — thin main: option table, then RunRoadMesh().
#include <cstdio>

#include "cli/app.h"
#include "cli/options.h"
#include "render/context.h"
#include "roadmesh.h"

int main(int argc, char** argv) {
  mvtm::RoadMeshOptions o;
  CLI::App app;
  mvtm::ConfigureApp(
      app, "roadmesh",
      "Build WS/mesh.ply from the workspace's sparse COLMAP model when there is no dense "
      "mesh: a corridor along the camera path (ground strip, side walls fitted to the "
      "sparse points, open sky) with normals and Lambertian vertex colours. Lengths are in "
      "metre-equivalents: metres for a metric model (--metric), else scaled by the camera height "
      "the scene shows (1.65 m).");
  app.add_option("WS", o.workspace, "Workspace folder (sparse/, images/)")->required();
  app.add_option("--width", o.width,
                 "Road width in metre-equivalents (0 < M <= 50): ground points within M/4 (else "
                 "M/2) of the path; walls at least M/2 + 1 away")
      ->capture_default_str();
  app.add_option("--wall-height", o.wall_height,
                 "Wall height above the ground in metre-equivalents (0 < M <= 200)")
      ->capture_default_str();
  app.add_option("--resolution", o.resolution,
                 "Grid spacing along and across in metre-equivalents (0.05 <= M <= 5)")
      ->capture_default_str();
  app.add_flag("--metric", o.metric,
               "The model is in metres: lengths are metres (else the model's unit is its camera "
               "height over 1.65 m)");
  app.add_flag("--no-colours", o.no_colours,
               "Write no vertex colours (no images, no OpenGL needed)");
  app.add_flag(
      "--dense", o.dense,
      "Fuse densify's depth maps (stereo/) into the mesh on a sparse signed-distance volume; the "
      "corridor's ground only where they leave holes");
  app.add_option("--voxel", o.voxel,
                 "--dense: voxel size as a fraction of the median camera spacing")
      ->capture_default_str();
  app.add_option("--max-depth", o.max_depth, "--dense: depth used, in median camera spacings")
      ->capture_default_str();
  app.add_option("--min-agree", o.min_agree, "--dense: other views that must confirm a depth pixel")
      ->capture_default_str();
  app.add_option("--ground-below", o.ground_below,
                 "--dense: lower the corridor ground by this many voxels under the fused surface "
                 "(0: at its fitted height)")
      ->capture_default_str();
  app.add_option(
         "--walls-behind", o.walls_behind,
         "--dense: move the corridor walls back by this many voxels behind the fused surface, "
         "so they show only through its holes (-1: no walls)")
      ->capture_default_str();
  app.add_flag("--force", o.force, "Replace an existing mesh");
  mvtm::AddChoiceOption(app, "--gl", o.gl, mvtm::GlBackendNames(), "OpenGL backend");
  mvtm::AddQuietOption(app, o.quiet);
  return mvtm::RunMain(app, "roadmesh", argc, argv, [&] {
    auto r = mvtm::RunRoadMesh(o);
    if (!o.quiet)
      std::fprintf(
          stderr,
          "roadmesh: %s: %zu vertices, %zu triangles; unit %.4g per metre (%s); in model units: "
          "path %.4g, camera height %.3g (%s), walls %.3g left / %.3g right; %zu ground vertices "
          "refined; %zu of %zu vertices coloured%s%s\n",
          r.mesh_path.c_str(), r.vertices, r.faces, r.unit.unit,
          mvtm::DescribeSceneUnit(r.unit).c_str(), r.path_length, r.camera_height,
          r.ground_points ? (std::to_string(r.ground_points) + " points").c_str() : "default",
          r.left_wall, r.right_wall, r.refined_vertices, r.coloured, r.vertices,
          r.gl.empty() ? "" : "; ", r.gl.c_str());
    if (!o.quiet && o.dense)
      std::fprintf(stderr,
                   "roadmesh: dense: %zu depth maps fused into %zu triangles; %zu corridor ground "
                   "and %zu wall triangles behind it close its holes\n",
                   r.dense_views, r.dense_faces, r.corridor_faces, r.corridor_wall_faces);
    return 0;
  });
}
