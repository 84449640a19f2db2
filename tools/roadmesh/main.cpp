// roadmesh — thin main: the declared option table, then RunRoadMesh().
#include <cstdio>

#include "cli/app.h"
#include "cli/options.h"
#include "roadmesh.h"

namespace {

constexpr const char* kAbout =
    "Build WS/mesh.ply from the workspace's sparse COLMAP model when there is no dense "
    "mesh: a corridor along the camera path (ground strip, side walls fitted to the "
    "sparse points, open sky) with normals and Lambertian vertex colours. Lengths are in "
    "metre-equivalents: metres for a metric model (--metric), else scaled by the camera height "
    "the scene shows (1.65 m).";

// Runs the tool and prints its summary; the exit status.
int RunAndReport(mvtm::RoadMeshOptions& o) {
  auto r = mvtm::RunRoadMesh(o);
  if (!o.quiet && r.up_to_date)
    std::fprintf(stderr, "roadmesh: %s is up to date (--force rebuilds it)\n", r.mesh_path.c_str());
  if (r.up_to_date) return 0;
  if (!o.quiet)
    std::fprintf(
        stderr,
        "roadmesh: %s: %zu vertices, %zu triangles; unit %.4g per metre (%s); in model "
        "units: "
        "path %.4g, camera height %.3g (%s), walls %.3g left / %.3g right; %zu ground "
        "vertices "
        "refined; %zu of %zu vertices coloured%s%s%s\n",
        r.mesh_path.c_str(), r.vertices, r.faces, r.unit.unit,
        mvtm::DescribeSceneUnit(r.unit).c_str(), r.path_length, r.camera_height,
        r.ground_points ? (std::to_string(r.ground_points) + " points").c_str() : "default",
        r.left_wall, r.right_wall, r.refined_vertices, r.coloured, r.vertices,
        r.gl.empty() ? "" : "; ", r.gl.c_str(), r.why.empty() ? "" : (" [" + r.why + "]").c_str());
  if (!o.quiet && o.dense)
    std::fprintf(
        stderr,
        "roadmesh: dense: %zu depth maps fused into %zu triangles; %zu corridor ground "
        "(lowered %.3g under the fused road) and %zu wall triangles behind it close its "
        "holes (%zu wall vertices just behind a fused facade, %zu where the photos saw through "
        "them)\n",
        r.dense_views, r.dense_faces, r.corridor_faces, r.ground_lowered, r.corridor_wall_faces,
        r.walls_at_facades, r.walls_seen);
  return 0;
}

}  // namespace

int main(int argc, char** argv) {
  mvtm::RoadMeshOptions o;
  return mvtm::RunTool(mvtm::DeclareOptions(o), kAbout, argc, argv,
                       [&] { return RunAndReport(o); });
}
