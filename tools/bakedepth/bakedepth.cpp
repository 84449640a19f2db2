#include "bakedepth.h"

#include <chrono>
#include <cmath>
#include <memory>
#include <set>

#include "base/atomic_file.h"
#include "base/error.h"
#include "cli/progress.h"
#include "image/image.h"
#include "io/colmap_model.h"
#include "io/mesh_io.h"
#include "render/context.h"
#include "render/renderer.h"
#include "run/ledger.h"
#include "workspace/road.h"
#include "workspace/road_meshes.h"
#include "workspace/workspace.h"

namespace mvtm {

OptionTable DeclareOptions(BakeDepthOptions& o) {
  OptionTable t("bakedepth");
  t.Positional("WS", &o.workspace,
               "Workspace folder (sparse/, mesh.ply), or a road (ROAD/Graph.txt: every "
               "fragment's images, baked against the fragment's and its neighbours' triangles)")
      .Dir();
  t.Real("--scale", &o.scale, "Depth map size relative to the image (0 < F <= 4)")
      .Range(0, 4, true)
      .Alternative("0.5");
  DeclareWorkOptions(t, o, "images", "in name order", "Rebake maps even when they are up to date");
  t.Choice("--gl", &o.gl, GlBackendTable(), "OpenGL backend");
  return t;
}

void BakeDepthOptions::Check() const { CheckDeclared(*this); }

namespace {

// Bakes the images `todo` of a workspace with `renderer`, recording each map in the ledger.
void BakeImages(const BakeDepthOptions& o, const Workspace& ws, const Reconstruction& rec,
                const std::vector<const ImageRecord*>& todo, Renderer& renderer, Ledger& ledger,
                const std::vector<fs::path>& item_inputs, BakeDepthReport& rep) {
  Progress bar("bakedepth", todo.size(), o.quiet);
  for (const ImageRecord* im : todo) {
    const Camera& cam = rec.cameras.at(im->camera_id);
    cam.RequireUndistorted();
    uint64_t w =
        std::max<uint64_t>(1, static_cast<uint64_t>(std::lround(double(cam.width) * o.scale)));
    uint64_t h =
        std::max<uint64_t>(1, static_cast<uint64_t>(std::lround(double(cam.height) * o.scale)));
    View v{o.scale == 1.0 ? cam : cam.Scaled(w, h), im->world_to_camera};
    auto t0 = std::chrono::steady_clock::now();
    Image depth = renderer.RenderDepth(v);
    auto t1 = std::chrono::steady_clock::now();
    WriteImage(ws.DepthPath(im->name).string(), depth);
    ledger.Done(ws.DepthPath(im->name), item_inputs);
    auto t2 = std::chrono::steady_clock::now();
    rep.render_ms += std::chrono::duration<double, std::milli>(t1 - t0).count();
    rep.write_ms += std::chrono::duration<double, std::milli>(t2 - t1).count();
    ++rep.written;
    bar.Step();
  }
}

// A road: each fragment's images (its own and its copies of the neighbours') baked against the
// road's mesh around it (its own triangles and its neighbours'), fragment by fragment, the next
// fragment's meshes read while one bakes. --frames and --shard count the road's recorded frames
// (a shard is a contiguous run of them); a frame chosen is baked in every fragment that holds it.
BakeDepthReport RunRoadBake(const BakeDepthOptions& o) {
  const Road road(o.workspace);
  const auto frames = road.RecordedFrames();
  std::set<std::string> names;
  // Shards are contiguous runs of the road's frames: each reads a few fragments, not all.
  for (size_t i : o.Select().ApplyBlocks(frames.size())) names.insert(frames[i].second);
  BakeDepthReport rep;
  rep.selected = names.size();
  BakeDepthOptions resolved = o;
  const OptionTable table = DeclareOptions(resolved);
  RoadMeshes meshes(road);
  std::unique_ptr<GlContext> ctx;
  for (size_t k = 0; k < road.fragments().size(); ++k) {
    const Workspace ws(road.fragments()[k].dir);
    const Reconstruction rec = ReadColmapModel(ws.SparseDir().string());
    const std::vector<fs::path> resident_inputs = road.ResidentFiles(k);
    Ledger ledger(ws.root(), o.ProvenanceName("bakedepth"), table, ws.SparseModelFiles(),
                  road.root());
    std::vector<const ImageRecord*> todo;
    for (const ImageRecord* im : rec.ImagesByName())
      if (names.count(im->name)) {
        if (ledger.Stale(ws.DepthPath(im->name), resident_inputs, o.force).empty())
          ++rep.skipped;
        else
          todo.push_back(im);
      }
    RemoveStaleTemporaries(ws.DepthDir());
    if (rep.why.empty()) rep.why = ledger.Summary();  // the first fragment's reasons stand
    if (todo.empty()) continue;
    const std::vector<size_t> next =
        k + 1 < road.fragments().size() ? road.Resident(k + 1) : std::vector<size_t>{};
    const Mesh mesh = meshes.Union(road.Resident(k), next);
    if (mesh.faces.empty())
      throw Error(ws.root().string(), 0, "no triangles in this fragment or its neighbours");
    if (!ctx) {
      ctx = GlContext::Create(o.gl);
      rep.gl = ctx->Describe();
    }
    Renderer renderer(mesh);
    BakeImages(o, ws, rec, todo, renderer, ledger, resident_inputs, rep);
    ledger.Write({{"gl_used", rep.gl}});
  }
  return rep;
}

}  // namespace

BakeDepthReport RunBakeDepth(const BakeDepthOptions& o) {
  o.Check();
  if (Road::IsRoad(o.workspace)) return RunRoadBake(o);
  Workspace ws(o.workspace);
  ws.Require("bakedepth", {WsItem::kSparse, WsItem::kMesh});
  Selection sel = o.Select();
  Reconstruction rec = ReadColmapModel(ws.SparseDir().string());
  auto images = rec.ImagesByName();
  auto chosen = sel.Apply(images.size());
  BakeDepthReport rep;
  rep.selected = chosen.size();
  const fs::path mesh_path = ws.MeshPath();
  std::vector<fs::path> inputs = ws.SparseModelFiles();
  inputs.push_back(mesh_path);
  BakeDepthOptions resolved = o;
  const OptionTable table = DeclareOptions(resolved);
  Ledger ledger(ws.root(), o.ProvenanceName("bakedepth"), table, inputs, ws.root());
  std::vector<const ImageRecord*> todo;
  for (size_t i : chosen) {
    if (ledger.Stale(ws.DepthPath(images[i]->name), {}, o.force).empty()) {
      ++rep.skipped;
      continue;
    }
    todo.push_back(images[i]);
  }
  rep.why = ledger.Summary();
  RemoveStaleTemporaries(ws.DepthDir());  // a killed run's leftovers, even when all is up to date
  if (!todo.empty()) {
    Mesh mesh = ReadMesh(mesh_path.string());
    if (mesh.faces.empty()) throw Error(mesh_path.string(), 0, "the mesh has no triangles");
    auto ctx = GlContext::Create(o.gl);
    rep.gl = ctx->Describe();
    Renderer renderer(mesh);
    BakeImages(o, ws, rec, todo, renderer, ledger, {}, rep);
    // Provenance is per run; with shards, each shard writes its own record.
    ledger.Write({{"gl_used", rep.gl}});
  }
  return rep;
}

}  // namespace mvtm
