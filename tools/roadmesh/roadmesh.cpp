#include "roadmesh.h"

#include <vector>

#include "base/error.h"
#include "cli/progress.h"
#include "image/image.h"
#include "io/colmap_model.h"
#include "io/mesh_io.h"
#include "mesh/corridor.h"
#include "mesh/vertex_colours.h"
#include "render/context.h"
#include "workspace/workspace.h"

namespace mvtm {

namespace {

// Checks the workspace holds what the run needs and no mesh (unless --force); returns where the
// new mesh goes. mesh.ply is the first name Workspace::MeshPath() looks for, so the new mesh wins.
fs::path PrepareWorkspace(const Workspace& ws, const RoadMeshOptions& o) {
  std::vector<WsItem> needs = {WsItem::kSparse};
  if (!o.no_colours) needs.push_back(WsItem::kImages);
  ws.Require("roadmesh", needs);
  const fs::path existing = ws.MeshPath();
  if (fs::exists(existing) && !o.force)
    throw Error(existing.string(), 0, "a mesh exists already (--force replaces it)");
  return ws.NewMeshPath();
}

// Vertex colours from the workspace's images (in name order); sets rep.gl and rep.coloured.
void BakeColours(const Workspace& ws, const Reconstruction& rec, const RoadMeshOptions& o,
                 Mesh& mesh, RoadMeshReport& rep) {
  auto ctx = GlContext::Create(ParseGlBackend(o.gl));
  rep.gl = ctx->Describe();
  VertexColourBaker baker(mesh);
  const auto images = rec.ImagesByName();
  Progress bar("roadmesh", images.size(), o.quiet);
  for (const ImageRecord* im : images) {
    const Camera& cam = rec.cameras.at(im->camera_id);
    cam.RequireUndistorted();  // before reading the image: the camera model is the first error
    baker.Add(cam, im->world_to_camera, ReadImage(ws.SourceImagePath(im->name).string()));
    bar.Step();
  }
  rep.coloured = baker.Finish(mesh);
}

void WriteRoadMeshProvenance(const Workspace& ws, const RoadMeshOptions& o,
                             const RoadMeshReport& rep) {
  std::vector<fs::path> inputs;
  for (const char* f : {"images", "cameras", "points3D"})
    for (const char* ext : {".txt", ".bin"})
      if (fs::exists(ws.SparseDir() / (std::string(f) + ext)))
        inputs.push_back(ws.SparseDir() / (std::string(f) + ext));
  nlohmann::json opts = {{"width", o.width},
                         {"wall_height", o.wall_height},
                         {"resolution", o.resolution},
                         {"no_colours", o.no_colours},
                         {"gl", rep.gl},
                         {"camera_height", rep.camera_height},
                         {"ground_points", rep.ground_points},
                         {"left_wall", rep.left_wall},
                         {"right_wall", rep.right_wall}};
  ws.WriteProvenance("roadmesh", opts, inputs);
}

}  // namespace

void RoadMeshOptions::Check() const {
  if (!(width > 0 && width <= 50)) throw UsageError("--width: must be in (0, 50] metres");
  if (!(wall_height > 0 && wall_height <= 200))
    throw UsageError("--wall-height: must be in (0, 200] metres");
  if (!(resolution >= 0.05 && resolution <= 5))
    throw UsageError("--resolution: must be in [0.05, 5] metres");
  ParseGlBackend(gl);
}

RoadMeshReport RunRoadMesh(const RoadMeshOptions& o) {
  o.Check();
  const Workspace ws(o.workspace);
  const fs::path out_path = PrepareWorkspace(ws, o);
  const Reconstruction rec = ReadColmapModel(ws.SparseDir().string());
  RoadMeshReport rep;
  rep.images = rec.images.size();
  rep.points = rec.points3D.size();
  if (rep.images < 2)
    throw Error(ws.SparseDir().string(), 0, "need at least two registered images to follow a path");

  Corridor corridor = BuildCorridor(rec, {o.width, o.wall_height, o.resolution});
  Mesh& mesh = corridor.mesh;
  rep.stations = corridor.stations;
  rep.path_length = corridor.path_length;
  rep.camera_height = corridor.camera_height;
  rep.ground_points = corridor.ground_points;
  rep.left_wall = corridor.left_wall;
  rep.right_wall = corridor.right_wall;
  rep.refined_vertices = corridor.refined_vertices;
  rep.vertices = mesh.vertices.size();
  rep.faces = mesh.faces.size();
  if (!o.no_colours) BakeColours(ws, rec, o, mesh, rep);

  WriteMesh(out_path.string(), mesh);
  rep.mesh_path = out_path.string();
  WriteRoadMeshProvenance(ws, o, rep);
  return rep;
}

}  // namespace mvtm
