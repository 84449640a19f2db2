#include "roadmesh.h"

#include <vector>

#include "base/error.h"
#include "cli/progress.h"
#include "fusion/fusion.h"
#include "image/image.h"
#include "io/colmap_model.h"
#include "io/mesh_io.h"
#include "mesh/corridor.h"
#include "mesh/merge.h"
#include "mesh/vertex_colours.h"
#include "render/context.h"
#include "stereo/neighbours.h"
#include "workspace/workspace.h"

namespace mvtm {

namespace {

// Checks the workspace holds what the run needs and no mesh (unless --force); returns where the
// new mesh goes. mesh.ply is the first name Workspace::MeshPath() looks for, so the new mesh wins.
fs::path PrepareWorkspace(const Workspace& ws, const RoadMeshOptions& o) {
  std::vector<WsItem> needs = {WsItem::kSparse};
  if (o.dense) needs.push_back(WsItem::kStereo);
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

// densify's depth maps with the cameras scaled to their size, in name order.
std::vector<DepthView> LoadStereoViews(const Workspace& ws, const Reconstruction& rec) {
  std::vector<DepthView> views;
  for (const ImageRecord* im : rec.ImagesByName()) {
    const fs::path d = ws.StereoDepthPath(im->name), c = ws.StereoConfidencePath(im->name);
    if (!fs::exists(d)) continue;
    DepthView v;
    v.depth = ReadImage(d.string());
    if (fs::exists(c)) v.confidence = ReadImage(c.string());
    const Camera& cam = rec.cameras.at(im->camera_id);
    cam.RequireUndistorted();
    v.camera = cam.Scaled(uint64_t(v.depth.width), uint64_t(v.depth.height));
    v.world_to_camera = im->world_to_camera;
    CheckDepthView(v, views.size());
    views.push_back(std::move(v));
  }
  if (views.empty())
    throw Error(ws.StereoDir().string(), 0, "no depth maps of the model's images (run densify)");
  return views;
}

// The fused surface of the stereo depth maps, closed by the corridor's ground where it has holes.
Mesh DenseMesh(const Workspace& ws, const Reconstruction& rec, const RoadMeshOptions& o,
               const Mesh& corridor, RoadMeshReport& rep) {
  const std::vector<DepthView> views = LoadStereoViews(ws, rec);
  FusionOptions fo;
  fo.consistency.min_agree = o.min_agree;
  fo.tsdf.voxel_per_spacing = o.voxel;
  fo.tsdf.max_depth_spacings = o.max_depth;
  const Mesh dense = FuseDepthViews(views, fo);
  std::vector<Rigid3d> w2c;
  for (const auto& v : views) w2c.push_back(v.world_to_camera);
  Eigen::Vector3d down, side;
  DriveAxes(w2c, down, side);
  MergeReport mr;
  const double voxel = o.voxel * MedianCameraSpacing(views);
  Mesh out = MergeGroundBeneath(dense, corridor, -down, o.ground_below * voxel, &mr);
  rep.dense_views = views.size();
  rep.dense_faces = dense.faces.size();
  rep.corridor_faces = mr.proxy_faces_kept;
  return out;
}

void WriteRoadMeshProvenance(const Workspace& ws, const RoadMeshOptions& o,
                             const RoadMeshReport& rep) {
  std::vector<fs::path> inputs;
  inputs = ws.SparseModelFiles();
  if (o.dense)
    for (const auto& e : fs::directory_iterator(ws.StereoDir())) inputs.push_back(e.path());
  nlohmann::json opts = {{"width", o.width},
                         {"wall_height", o.wall_height},
                         {"resolution", o.resolution},
                         {"no_colours", o.no_colours},
                         {"dense", o.dense},
                         {"voxel", o.voxel},
                         {"max_depth", o.max_depth},
                         {"min_agree", o.min_agree},
                         {"ground_below", o.ground_below},
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
  if (!(voxel > 0 && voxel <= 10)) throw UsageError("--voxel: must be in (0, 10] camera spacings");
  if (!(max_depth > 0 && max_depth <= 1000))
    throw UsageError("--max-depth: must be in (0, 1000] camera spacings");
  if (min_agree < 1 || min_agree > 16) throw UsageError("--min-agree: must be 1..16");
  if (!(ground_below >= 0 && ground_below <= 100))
    throw UsageError("--ground-below: must be in [0, 100] voxels");
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
  if (o.dense) corridor.mesh = DenseMesh(ws, rec, o, corridor.mesh, rep);
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
