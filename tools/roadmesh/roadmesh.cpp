#include "roadmesh.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>
#include <unordered_map>
#include <vector>

#include "base/atomic_file.h"
#include "base/error.h"
#include "base/stats.h"
#include "cli/progress.h"
#include "cli/work.h"
#include "fusion/fusion.h"
#include "image/image.h"
#include "io/colmap_model.h"
#include "io/mesh_io.h"
#include "mesh/corridor.h"
#include "mesh/merge.h"
#include "mesh/vertex_colours.h"
#include "render/context.h"
#include "run/ledger.h"
#include "stereo/neighbours.h"
#include "workspace/assets.h"
#include "workspace/workspace.h"

namespace mvtm {

namespace {

constexpr double kDashcamHeight = 1.65;  // metres (KITTI); the unit is the height over this
constexpr double kTypicalSpacing = 1.0;  // metres between frames, for the fallback only
constexpr double kLowRows = 0.6;         // the bottom 40 % of the rows look at the road
constexpr size_t kMinImagePoints = 5, kMinHeightImages = 3;

// The height of a point below the camera nearest to it when it lies in that camera's lane
// (see SceneUnit), else NaN.
double HeightBelowNearest(const Eigen::Vector3d& x, const std::vector<Rigid3d>& w2c,
                          const std::vector<Eigen::Vector3d>& centres) {
  size_t best = 0;
  for (size_t j = 1; j < centres.size(); ++j)
    if ((x - centres[j]).squaredNorm() < (x - centres[best]).squaredNorm()) best = j;
  const Eigen::Vector3d v = w2c[best].q * (x - centres[best]);  // camera axes
  const double h = v.y();
  return h > 0 && std::abs(v.x()) <= h && std::abs(v.z()) <= h
             ? h
             : std::numeric_limits<double>::quiet_NaN();
}

// Per image, the median height of its road points (images with too few are left out); `w2c` the
// images' normalised poses; `points` counts the heights used.
std::vector<double> ImageGroundHeights(const Reconstruction& rec,
                                       const std::vector<const ImageRecord*>& images,
                                       const std::vector<Rigid3d>& w2c, size_t& points) {
  std::vector<Eigen::Vector3d> centres;
  for (const Rigid3d& p : w2c) centres.push_back(p.Centre());
  std::unordered_map<uint64_t, double> height;  // by point id, NaN: not a road point
  std::vector<double> per_image;
  points = 0;
  for (const ImageRecord* im : images) {
    const Camera& cam = rec.cameras.at(im->camera_id);
    const double low = std::max(cam.cy(), kLowRows * double(cam.height));
    std::vector<double> hs;
    for (const Point2D& p : im->points2D) {
      const auto pt = rec.points3D.find(p.point3D_id);
      if (p.xy.y() < low || pt == rec.points3D.end()) continue;
      auto [it, fresh] = height.try_emplace(p.point3D_id, 0.0);
      if (fresh) it->second = HeightBelowNearest(pt->second.xyz, w2c, centres);
      if (!std::isnan(it->second)) hs.push_back(it->second);
    }
    if (hs.size() < kMinImagePoints) continue;
    points += hs.size();
    per_image.push_back(Median(hs));
  }
  return per_image;
}

// Throws unless the workspace holds what the run needs.
void RequireInputs(const Workspace& ws, const RoadMeshOptions& o) {
  std::vector<WsItem> needs = {WsItem::kSparse};
  if (o.dense) needs.push_back(WsItem::kStereo);
  if (!o.no_colours) needs.push_back(WsItem::kImages);
  ws.Require("roadmesh", needs);
}

// The files the mesh is made from: the model, the images that colour it and their masks, and
// with --dense densify's maps (missing ones are left out; one that appears makes the mesh stale).
// The colours come from images/, never from textures/: inpaint3d makes those from the mesh (its
// depth, its vertex colours) and blends a seam outside each mask, so a mesh coloured from them
// would be stale again after every inpaint3d, and a rerun of the road build would never settle.
std::vector<fs::path> MeshInputs(const Workspace& ws, const Reconstruction& rec,
                                 const RoadMeshOptions& o) {
  std::vector<fs::path> in = ws.SparseModelFiles();
  for (const ImageRecord* im : rec.ImagesByName()) {
    if (!o.no_colours) in.push_back(ws.ImagePath(im->name));
    // Masked pixels (vehicles: segtrack or dynmask; a video's overlay) are left out of the
    // colours and of fusion: a mask that appears or changes makes the mesh stale.
    if (fs::exists(ws.MaskPath(im->name))) in.push_back(ws.MaskPath(im->name));
    if (o.dense) {
      in.push_back(ws.StereoDepthPath(im->name));
      in.push_back(ws.StereoConfidencePath(im->name));
    }
  }
  return in;
}

// Why mesh.ply must be (re)built, "" when it is up to date. A mesh roadmesh did not make (or one
// edited since) is refused unless --force; mesh.ply is the first name Workspace::MeshPath()
// looks for, so the new mesh wins over COLMAP's.
std::string MeshStale(const Workspace& ws, const RoadMeshOptions& o, Ledger& ledger) {
  const fs::path out = ws.NewMeshPath(), existing = ws.MeshPath();
  const std::string why = ledger.Stale(out, {}, o.force);
  if (!o.force && fs::exists(existing) && (existing != out || why == "no record"))
    throw Error(existing.string(), 0, "a mesh exists already (--force replaces it)");
  return why;
}

// Vertex colours from the workspace's images (in name order); sets rep.gl and rep.coloured.
void BakeColours(const Workspace& ws, const Reconstruction& rec, const RoadMeshOptions& o,
                 Mesh& mesh, RoadMeshReport& rep) {
  auto ctx = GlContext::Create(o.gl);
  rep.gl = ctx->Describe();
  VertexColourBaker baker(mesh);
  const auto images = rec.ImagesByName();
  Progress bar("roadmesh", images.size(), o.quiet);
  for (const ImageRecord* im : images) {
    const Camera& cam = rec.cameras.at(im->camera_id);
    cam.RequireUndistorted();  // before reading the image: the camera model is the first error
    const std::string path = ws.ImagePath(im->name).string();  // see MeshInputs
    Image img = ReadImage(path);
    RequireImageSize(img, path, cam.width, cam.height);
    baker.Add(cam, im->world_to_camera, img, ReadMaskAtCamera(ws, im->name, cam));
    bar.Step();
  }
  rep.coloured = baker.Finish(mesh);
}

// Sets the depth of masked pixels (mask at the image's size, depth at any size) to +inf: what
// moved is not fused.
void LeaveOutMasked(const Image& mask, Image& depth) {
  if (mask.data.empty()) return;
  const Image m = ResizeNearest(mask, depth.width, depth.height);
  for (size_t k = 0; k < depth.data.size(); ++k)
    if (m.data[k * size_t(m.channels)] != 0) depth.data[k] = std::numeric_limits<float>::infinity();
}

// densify's depth maps with the cameras scaled to their size, in name order.
std::vector<DepthView> LoadStereoViews(const Workspace& ws, const Reconstruction& rec) {
  std::vector<DepthView> views;
  FinishInterruptedWrites(ws.StereoDir());  // a pair a killed densify had removed: back first
  for (const ImageRecord* im : rec.ImagesByName()) {
    const fs::path d = ws.StereoDepthPath(im->name), c = ws.StereoConfidencePath(im->name);
    if (!fs::exists(d)) continue;
    DepthView v;
    {
      // densify killed between a pair's renames: both new; a live one's renames waited for.
      const FolderLock lock = LockForReading(ws.StereoDir());
      v.depth = ReadFloatMap(d.string());
      if (fs::exists(c)) v.confidence = ReadFloatMap(c.string());
    }
    const Camera& cam = rec.cameras.at(im->camera_id);
    cam.RequireUndistorted();
    v.camera = cam.Scaled(uint64_t(v.depth.width), uint64_t(v.depth.height));
    v.world_to_camera = im->world_to_camera;
    LeaveOutMasked(ReadMaskAtCamera(ws, im->name, cam), v.depth);
    CheckDepthView(v, views.size());
    views.push_back(std::move(v));
  }
  if (views.empty())
    throw Error(ws.StereoDir().string(), 0, "no depth maps of the model's images (run densify)");
  return views;
}

// Each view's pixels as sights from its camera centre: every second pixel of every second row,
// fewer (every third, fourth, ...) when that would make more than kMaxSights in all (a long road
// in one workspace: memory stays bounded, every stretch of wall still gets many).
constexpr size_t kMaxSights = 8'000'000;
std::vector<Sight> Sights(const std::vector<DepthView>& views) {
  size_t pixels = 0;
  for (const DepthView& v : views) pixels += size_t(v.depth.width) * size_t(v.depth.height);
  int stride = 2;
  while (pixels / size_t(stride * stride) > kMaxSights) ++stride;
  std::vector<Sight> out;
  out.reserve(pixels / size_t(stride * stride));
  for (const DepthView& v : views) {
    const Rigid3d c2w = v.world_to_camera.Inverse();
    const Eigen::Vector3d centre = c2w.t;
    for (int y = stride / 2; y < v.depth.height; y += stride)
      for (int x = stride / 2; x < v.depth.width; x += stride) {
        const float z = v.depth.at(x, y);
        if (std::isfinite(z) && z > 0)
          out.push_back({centre, c2w * v.camera.Unproject({x + 0.5, y + 0.5}, z)});
      }
  }
  return out;
}

// The fused surface of the stereo depth maps, closed by the corridor's ground where it has holes.
Mesh DenseMesh(const Workspace& ws, const Reconstruction& rec, const RoadMeshOptions& o,
               const Mesh& corridor, RoadMeshReport& rep) {
  std::vector<DepthView> views = LoadStereoViews(ws, rec);
  FusionOptions fo;
  fo.consistency.min_agree = o.min_agree;
  fo.consistency.witnessed = !o.strict_agree;
  fo.consistency.relative_tolerance = o.agree_tolerance;
  fo.tsdf.voxel_per_spacing = o.voxel;
  fo.tsdf.max_depth_spacings = o.max_depth;
  // The depths other photos confirm, once: what fusion integrates and the sights of the seen
  // walls below (a depth one photo alone claims is as often the sweep's error, a facade's
  // repeated windows matched a plane too far, as scenery seen through a hole).
  std::vector<Image> confirmed = FilterConsistentDepth(views, fo.consistency);
  for (size_t i = 0; i < views.size(); ++i) views[i].depth = std::move(confirmed[i]);
  fo.filter = false;
  const Mesh dense = FuseDepthViews(views, fo);
  std::vector<Rigid3d> w2c;
  for (const auto& v : views) w2c.push_back(v.world_to_camera);
  Eigen::Vector3d down, side;
  DriveAxes(w2c, down, side);
  MergeReport mr;
  const double spacing = MedianCameraSpacing(views), voxel = o.voxel * spacing;
  // The corridor's ground comes from a camera height fitted to a few sparse points: where it lies
  // above the fused road it would hide it, so it goes down to it (where the fused road has holes
  // the corridor shows at the fused road's height).
  const double unit = o.metric ? 1.0 : rep.unit.unit;
  const double above = ProxyGroundAbove(dense, corridor, -down, o.resolution * unit, 0.5 * unit);
  rep.ground_lowered = o.ground_below * voxel + std::max(0.0, above);
  std::vector<double> wall_offsets;
  if (o.walls_gap >= 0 && o.walls_behind >= 0) {
    // Facade faces within 4 resolutions along the wall and 2 up or down (2 and 1 m-eq. at the
    // default); a facade is flat (interquartile range of its distances within 0.3 m-eq.: not a
    // hedge or a tree) and lies from 3 m-eq. in front of the fitted wall to 30 behind it.
    FacadeSearch fs;
    fs.reach = 4 * o.resolution * unit;
    fs.rise = 2 * o.resolution * unit;
    fs.front = 3 * unit;
    fs.back = 30 * unit;
    fs.spread = 0.3 * unit;
    fs.quantile = 0.5;
    wall_offsets = DenseFacadeBehindWalls(dense, corridor, -down, fs);
    for (double& w : wall_offsets)
      if (std::isfinite(w)) w += o.walls_gap * voxel, ++rep.walls_at_facades;
  }
  if (!o.no_seen_walls && o.walls_behind >= 0) {
    // Each stretch of wall where the photos saw through it: the median distance behind it of
    // the sights (confirmed depths) that meet it within --walls-reach along and half that up or
    // down through holes of the fused surface, at most --max-depth behind, and at least as far as
    // most of the fused surface they meet behind it.
    SeenWallSearch ss;
    ss.reach = o.walls_reach * unit;
    ss.rise = o.walls_reach / 2 * unit;
    ss.back = o.max_depth * spacing;
    const std::vector<double> seen = SeenWallDistances(corridor, -down, Sights(views), dense, ss);
    if (wall_offsets.empty()) wall_offsets.assign(seen.size(), NAN);
    for (size_t v = 0; v < seen.size(); ++v)
      if (std::isfinite(seen[v]) && !std::isfinite(wall_offsets[v]))
        wall_offsets[v] = seen[v], ++rep.walls_seen;
  }
  Mesh out = MergeProxyBehind(dense, corridor, -down, rep.ground_lowered, o.walls_behind * voxel,
                              &mr, wall_offsets);
  rep.dense_views = views.size();
  rep.dense_faces = dense.faces.size();
  rep.corridor_faces = mr.ground_faces;
  rep.corridor_wall_faces = mr.wall_faces;
  return out;
}

// What the record keeps beside the options: the unit and the fitted corridor (model units).
nlohmann::json RunFacts(const RoadMeshReport& rep) {
  return {{"gl_used", rep.gl},
          {"unit", rep.unit.unit},
          {"unit_source", rep.unit.source},
          {"camera_height", rep.camera_height},
          {"ground_points", rep.ground_points},
          {"left_wall", rep.left_wall},
          {"right_wall", rep.right_wall},
          {"ground_lowered", rep.ground_lowered},
          {"walls_at_facades", rep.walls_at_facades},
          {"walls_seen", rep.walls_seen}};
}

}  // namespace

SceneUnit EstimateSceneUnit(const Reconstruction& rec) {
  SceneUnit su;
  const auto images = rec.ImagesByName();
  std::vector<Rigid3d> w2c;
  for (const ImageRecord* im : images)
    w2c.emplace_back(NormalizedQuaternion(im->world_to_camera.q), im->world_to_camera.t);
  const std::vector<double> heights = ImageGroundHeights(rec, images, w2c, su.points);
  su.spacing = MedianSpacing(w2c);
  if (heights.size() >= kMinHeightImages) {
    su.source = "camera height";
    su.images = heights.size();
    su.camera_height = Median(heights);
    su.unit = su.camera_height / kDashcamHeight;
  } else if (su.spacing > 0) {
    su.source = "camera spacing";
    su.unit = su.spacing / kTypicalSpacing;
  } else {
    su.source = "none";  // the cameras do not move: the corridor refuses the model anyway
  }
  return su;
}

std::string DescribeSceneUnit(const SceneUnit& su) {
  char buf[160];
  const std::string source = su.source;
  if (source == "camera height")
    std::snprintf(buf, sizeof buf, "camera height %.4g from %zu points in %zu images / 1.65 m",
                  su.camera_height, su.points, su.images);
  else if (source == "camera spacing")
    std::snprintf(buf, sizeof buf,
                  "median camera spacing %.4g / 1 m: too few road points below the cameras",
                  su.spacing);
  else if (source == "none")
    std::snprintf(buf, sizeof buf, "the cameras do not move");
  else
    std::snprintf(buf, sizeof buf, "%s", su.source);
  return buf;
}

OptionTable DeclareOptions(RoadMeshOptions& o) {
  OptionTable t("roadmesh");
  t.Positional("WS", &o.workspace, "Workspace folder (sparse/, images/)").Dir();
  t.Real("--width", &o.width,
         "Road width in metre-equivalents (0 < M <= 50): ground points within M/4 (else "
         "M/2) of the path; walls at least M/2 + 1 away")
      .Range(0, 50, true);
  t.Real("--wall-height", &o.wall_height,
         "Wall height above the ground in metre-equivalents (0 < M <= 200)")
      .Range(0, 200, true);
  t.Real("--resolution", &o.resolution,
         "Grid spacing along and across in metre-equivalents (0.05 <= M <= 5)")
      .Range(0.05, 5);
  t.Flag("--metric", &o.metric,
         "The model is in metres: lengths are metres (else the model's unit is its camera "
         "height over 1.65 m)");
  t.Flag("--no-colours", &o.no_colours, "Write no vertex colours (no images, no OpenGL needed)");
  t.Flag("--dense", &o.dense,
         "Fuse densify's depth maps (stereo/) into the mesh on a sparse signed-distance volume; "
         "the corridor's ground only where they leave holes");
  t.Real("--voxel", &o.voxel, "--dense: voxel size as a fraction of the median camera spacing")
      .Range(0, 10, true);
  t.Real("--max-depth", &o.max_depth, "--dense: depth used, in median camera spacings")
      .Range(0, 1000, true);
  t.Integer("--min-agree", &o.min_agree,
            "--dense: other views that must confirm a depth pixel (fewer where fewer views see "
            "that far along their rays)")
      .Range(1, 16);
  t.Real("--agree-tolerance", &o.agree_tolerance,
         "--dense: a view confirms a depth pixel within this fraction of the depth")
      .Range(0, 1, true, true);
  t.Flag("--strict-agree", &o.strict_agree,
         "--dense: --min-agree confirming views even where fewer views see the pixel's point");
  t.Real("--ground-below", &o.ground_below,
         "--dense: lower the corridor ground by this many voxels under the fused surface "
         "(0: at its fitted height, or just under the fused road where it lies above it)")
      .Range(0, 100);
  t.Real("--walls-behind", &o.walls_behind,
         "--dense: move the corridor walls back by this many voxels behind the fused surface, "
         "so they show only through its holes, where no photo saw through them (everywhere "
         "with --no-seen-walls; -1: no walls)")
      .Range(-1, 1000);
  t.Real("--walls-gap", &o.walls_gap,
         "--dense: where the fused surface shows a flat facade near a wall, put the wall this "
         "many voxels behind it instead (-1: never)")
      .Range(-1, 1000);
  t.Real("--walls-reach", &o.walls_reach,
         "--dense: a wall vertex goes to the median distance seen behind the wall through holes "
         "of the fused surface within this many metre-equivalents along it and half as many up "
         "or down")
      .Range(0.05, 100);
  t.Flag("--no-seen-walls", &o.no_seen_walls,
         "--dense: every wall at --walls-behind (not at the median distance the photos saw "
         "behind it)");
  t.Flag("--force", &o.force, "Replace an existing mesh").Cosmetic();
  t.Choice("--gl", &o.gl, GlBackendTable(), "OpenGL backend");
  DeclareQuietOption(t, o.quiet);
  return t;
}

void RoadMeshOptions::Check() const { CheckDeclared(*this); }

RoadMeshReport RunRoadMesh(const RoadMeshOptions& o) {
  o.Check();
  const Workspace ws(o.workspace);
  RequireInputs(ws, o);
  const Reconstruction rec = ReadColmapModel(ws.SparseDir().string());
  RoadMeshOptions resolved = o;
  const OptionTable table = DeclareOptions(resolved);
  // The mesh is in the workspace: its record, provenance/roadmesh.json ("metric" among its
  // options is what Workspace::MetricRecord looks for).
  Ledger ledger(ws.root(), "roadmesh", table, MeshInputs(ws, rec, o), ws.root());
  RoadMeshReport rep;
  rep.mesh_path = ws.NewMeshPath().string();
  if (MeshStale(ws, o, ledger).empty()) {
    rep.up_to_date = true;
    return rep;
  }
  rep.why = ledger.Summary();
  rep.images = rec.images.size();
  rep.points = rec.points3D.size();
  if (rep.images < 2)
    throw Error(ws.SparseDir().string(), 0, "need at least two registered images to follow a path");

  if (!o.metric) rep.unit = EstimateSceneUnit(rec);
  Corridor corridor = BuildCorridor(rec, {o.width, o.wall_height, o.resolution, rep.unit.unit});
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

  WriteMesh(rep.mesh_path, mesh);
  ledger.Done(rep.mesh_path);
  ledger.Write(RunFacts(rep));
  return rep;
}

}  // namespace mvtm
