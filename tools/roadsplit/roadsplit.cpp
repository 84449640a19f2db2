#include "roadsplit.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <map>
#include <set>

#include "base/atomic_file.h"
#include "base/error.h"
#include "base/text.h"
#include "cli/work.h"
#include "index/path_index.h"
#include "io/colmap_model.h"
#include "io/exposure_tsv.h"
#include "io/mesh_io.h"
#include "run/ledger.h"
#include "workspace/road.h"
#include "workspace/workspace.h"

namespace mvtm {

OptionTable DeclareOptions(RoadSplitOptions& o) {
  OptionTable t("roadsplit");
  t.Positional("WS", &o.workspace,
               "Workspace to split (sparse/; images/, mesh.ply and every per-image folder go "
               "with their images)")
      .Dir();
  t.Positional("ROAD", &o.road, "Road folder to create (Graph.txt, Models/SEQ/FRAGMENT/)").Dir();
  t.Real("--length", &o.length,
         "Target fragment length along the path, in the model's units (metres once georef'd); "
         "the path is cut into equal fragments nearest this length")
      .Range(1, 1e9);
  t.Real("--overlap", &o.overlap,
         "Length each fragment also holds of its neighbours' stretches (images and triangles), "
         "model units")
      .Range(0, 1e9);
  t.Real("--junction-radius", &o.junction_radius,
         "A junction is where the path passes within this distance of an earlier stretch of "
         "itself (a loop), model units; 0: no junctions")
      .Range(0, 1e9);
  t.Flag("--force", &o.force, "Rewrite the road even when it is up to date").Cosmetic();
  DeclareQuietOption(t, o.quiet);
  return t;
}

void RoadSplitOptions::Check() const {
  CheckDeclared(*this);
  std::error_code ec;
  if (fs::exists(road) && fs::equivalent(workspace, road, ec))
    throw UsageError("ROAD must not be WS");
}

namespace {

// The sampling step of the path of record's PathIndex.
double PathStep(const RoadSplitOptions& o) { return std::max(o.length / 200, 1e-9); }

// The sequence an image belongs to: its folder and its name's stem up to the last '_'
// ("A_0007.png" → "A", "cam1/000001.png" → "cam1/"), "" for a bare name without one.
std::string SequenceOf(const std::string& name) {
  const fs::path p(name);
  const std::string stem = p.stem().string();
  const size_t u = stem.rfind('_');
  const std::string dir = p.parent_path().empty() ? "" : p.parent_path().string() + "/";
  return dir + (u == std::string::npos ? "" : stem.substr(0, u));
}

// A sequence's folder name under Models/: its key with '/' as '_' ("seq" for "").
std::string SequenceFolder(const std::string& key) {
  std::string f = key;
  while (!f.empty() && f.back() == '/') f.pop_back();
  for (char& c : f)
    if (c == '/') c = '_';
  return f.empty() ? "seq" : f;
}

struct Plan {
  std::vector<const ImageRecord*> record;  // the path of record, in order
  std::unique_ptr<PathIndex> path;
  std::string seq;                        // its folder name under Models/
  std::vector<double> bounds;             // fragment k owns s in [bounds[k], bounds[k+1])
  std::vector<double> image_s;            // per image (ImagesByName order)
  std::vector<std::set<size_t>> members;  // per fragment: image indices it holds
  std::vector<size_t> owner;              // per image
  std::vector<RoadFragment> fragments;
};

size_t FragmentAt(const Plan& p, double s) {
  auto it = std::upper_bound(p.bounds.begin() + 1, p.bounds.end() - 1, s);
  return static_cast<size_t>(it - (p.bounds.begin() + 1));
}

// The fragments whose stretch, grown by the overlap, holds s.
std::vector<size_t> FragmentsNear(const Plan& p, double s, double overlap) {
  std::vector<size_t> out;
  for (size_t k = 0; k + 1 < p.bounds.size(); ++k)
    if (s >= p.bounds[k] - overlap && s <= p.bounds[k + 1] + overlap) out.push_back(k);
  return out;
}

void PlanPath(const RoadSplitOptions& o, const std::vector<const ImageRecord*>& images, Plan& p) {
  std::map<std::string, std::vector<const ImageRecord*>> seqs;
  for (const ImageRecord* im : images) seqs[SequenceOf(im->name)].push_back(im);
  for (auto& [key, list] : seqs)  // the longest sequence (the first by name among equals)
    if (list.size() >= 2 && list.size() > p.record.size()) {
      p.record = list;
      p.seq = SequenceFolder(key);
    }
  if (p.record.empty())
    throw Error(o.workspace, 0, "no sequence of two or more images to take as the path");
  std::vector<Eigen::Vector3d> centres;
  for (const ImageRecord* im : p.record) centres.push_back(im->world_to_camera.Centre());
  double length = 0;
  for (size_t i = 1; i < centres.size(); ++i) length += (centres[i] - centres[i - 1]).norm();
  if (length / o.length > 1e5)
    throw Error(Workspace(o.workspace).SparseDir().string(), 0,
                "the path of record is " + FormatDouble(length) + " long, " +
                    FormatDouble(length / o.length) +
                    " fragments of --length: is a camera far from the others?");
  // Samples every 1/200 of a fragment: exact answers come from the segments around them.
  p.path = std::make_unique<PathIndex>(centres, PathStep(o));
  const double total = p.path->Length();
  if (!(total > 0)) throw Error(o.workspace, 0, "the path of record does not move");
  // At most one fragment per step of the path, so each owns an image of it.
  const double want = std::min(std::round(total / o.length), double(p.record.size() - 1));
  const size_t k = std::max<size_t>(1, static_cast<size_t>(want));
  const double len = total / double(k);
  if (k > 1 && len <= 2 * o.overlap)
    throw UsageError("--overlap " + FormatDouble(o.overlap) + ": fragments of " +
                     FormatDouble(len) +
                     " would not be longer than twice the overlap (lengthen --length or "
                     "shorten --overlap)");
  for (size_t i = 0; i <= k; ++i) p.bounds.push_back(total * double(i) / double(k));
}

void AssignImages(const RoadSplitOptions& o, const std::vector<const ImageRecord*>& images,
                  Plan& p) {
  std::map<const ImageRecord*, double> record_s;
  for (size_t i = 0; i < p.record.size(); ++i) record_s[p.record[i]] = p.path->ArcLength(i);
  p.members.resize(p.bounds.size() - 1);
  for (size_t i = 0; i < images.size(); ++i) {
    auto it = record_s.find(images[i]);
    const double s =
        it != record_s.end() ? it->second : p.path->Locate(images[i]->world_to_camera.Centre()).s;
    p.image_s.push_back(s);
    p.owner.push_back(FragmentAt(p, s));
    for (size_t f : FragmentsNear(p, s, o.overlap)) p.members[f].insert(i);
  }
}

std::string FragmentName(size_t k) {
  std::string n = std::to_string(k);
  return std::string(n.size() < 3 ? 3 - n.size() : 0, '0') + n;
}

// Links fragments a and b at `image` (both hold it) unless they are linked already.
bool Link(Plan& p, const std::vector<const ImageRecord*>& images, size_t a, size_t b,
          size_t image) {
  for (const RoadLink& l : p.fragments[a].links)
    if (l.to == b) return false;
  p.fragments[a].links.push_back({b, images[image]->name});
  p.fragments[b].links.push_back({a, images[image]->name});
  p.members[a].insert(image);
  p.members[b].insert(image);
  return true;
}

// Junctions: record images within the radius of a record image of a stretch more than a
// fragment and two overlaps away. The images are hashed by cells of the radius: each meets only
// those in the 27 cells around it, in the order of the path (as a scan of every pair would, in
// linear time). Returns the junction count.
size_t LinkJunctions(const RoadSplitOptions& o, const std::vector<const ImageRecord*>& images,
                     Plan& p) {
  std::map<const ImageRecord*, size_t> index;
  for (size_t i = 0; i < images.size(); ++i) index[images[i]] = i;
  const double apart = o.length + 2 * o.overlap;
  // Cells a little larger than the radius (a pair exactly at it stays in adjacent cells), and
  // not tiny (cell indices of UTM coordinates stay far inside int64).
  const double size = std::max(o.junction_radius, 1e-3) * (1 + 1e-9);
  auto cell = [&](size_t r) {
    const Eigen::Vector3d q = (p.record[r]->world_to_camera.Centre() / size).array().floor();
    return std::array<int64_t, 3>{int64_t(q.x()), int64_t(q.y()), int64_t(q.z())};
  };
  std::map<std::array<int64_t, 3>, std::vector<size_t>> cells;
  for (size_t r = 0; r < p.record.size(); ++r) cells[cell(r)].push_back(r);
  size_t junctions = 0;
  for (size_t a = 0; a < p.record.size(); ++a) {
    std::vector<size_t> near;
    const std::array<int64_t, 3> at = cell(a);
    for (int64_t dx = -1; dx <= 1; ++dx)
      for (int64_t dy = -1; dy <= 1; ++dy)
        for (int64_t dz = -1; dz <= 1; ++dz) {
          const auto it = cells.find({at[0] + dx, at[1] + dy, at[2] + dz});
          if (it == cells.end()) continue;
          for (size_t b : it->second)
            if (b > a) near.push_back(b);
        }
    std::sort(near.begin(), near.end());
    for (size_t b : near) {
      if (p.path->ArcLength(b) - p.path->ArcLength(a) <= apart) continue;
      const Eigen::Vector3d ca = p.record[a]->world_to_camera.Centre();
      const Eigen::Vector3d cb = p.record[b]->world_to_camera.Centre();
      if ((ca - cb).norm() > o.junction_radius) continue;
      const size_t ia = index[p.record[a]], ib = index[p.record[b]];
      const size_t fa = p.owner[ia], fb = p.owner[ib];
      if (fa == fb) continue;
      p.members[fa].insert(ib);
      p.members[fb].insert(ia);
      if (Link(p, images, fa, fb, ib)) ++junctions;
    }
  }
  return junctions;
}

// Neighbours along the path, then junctions (LinkJunctions). Returns the junction count.
size_t LinkFragments(const RoadSplitOptions& o, const std::vector<const ImageRecord*>& images,
                     Plan& p) {
  const size_t n = p.bounds.size() - 1;
  for (size_t k = 0; k + 1 < n; ++k) {
    // The pose where a drive passes on: the first image the next fragment owns.
    size_t first = images.size();
    for (size_t i = 0; i < images.size() && first == images.size(); ++i)
      if (p.owner[i] == k + 1 && SequenceOf(images[i]->name) == SequenceOf(p.record[0]->name))
        first = i;
    if (first == images.size())
      for (size_t i = 0; i < images.size() && first == images.size(); ++i)
        if (p.owner[i] == k + 1) first = i;
    if (first == images.size())
      throw Error(o.workspace, 0, "fragment " + FragmentName(k + 1) + " owns no image");
    Link(p, images, k, k + 1, first);
  }
  return o.junction_radius > 0 ? LinkJunctions(o, images, p) : 0;
}

// The fragment's model: its images, the cameras they use, the points seen by two of them.
Reconstruction SubModel(const Reconstruction& rec, const std::vector<const ImageRecord*>& images,
                        const std::set<size_t>& members) {
  Reconstruction out;
  std::set<uint32_t> ids;
  for (size_t i : members) {
    ids.insert(images[i]->id);
    out.images[images[i]->id] = *images[i];
    out.cameras[images[i]->camera_id] = rec.cameras.at(images[i]->camera_id);
  }
  for (const auto& [id, pt] : rec.points3D) {
    Point3D q = pt;
    q.track.clear();
    for (const TrackElement& t : pt.track)
      if (ids.count(t.image_id)) q.track.push_back(t);
    if (q.track.size() >= 2) out.points3D[id] = std::move(q);
  }
  for (auto& [id, im] : out.images)
    for (Point2D& pt : im.points2D)
      if (pt.point3D_id != kInvalidPoint3DId && !out.points3D.count(pt.point3D_id))
        pt.point3D_id = kInvalidPoint3DId;
  return out;
}

// Hard-links `from` to `to` (a copy across file systems); false when `from` does not exist.
bool LinkFile(const fs::path& from, const fs::path& to, RoadSplitReport& rep) {
  if (!fs::exists(from)) return false;
  CreateFolder(to.parent_path());
  std::error_code ec;
  const bool linked = LinkOrCopy(from, to, ec);
  if (ec) throw Error(to.string(), 0, "cannot copy " + from.string() + ": " + ec.message());
  ++(linked ? rep.linked : rep.copied);
  return true;
}

void LinkImageFiles(const Workspace& src, const Workspace& dst, const std::string& name,
                    RoadSplitReport& rep) {
  LinkFile(src.ImagePath(name), dst.ImagePath(name), rep);
  LinkFile(src.TexturePath(name), dst.TexturePath(name), rep);
  LinkFile(src.MaskPath(name), dst.MaskPath(name), rep);
  LinkFile(src.LabelPath(name), dst.LabelPath(name), rep);
  LinkFile(src.DynamicPath(name), dst.DynamicPath(name), rep);
  LinkFile(src.DepthPath(name), dst.DepthPath(name), rep);
  const FolderLock lock = LockForReading(src.StereoDir());  // densify's pair, one run's whole
  LinkFile(src.StereoDepthPath(name), dst.StereoDepthPath(name), rep);
  LinkFile(src.StereoConfidencePath(name), dst.StereoConfidencePath(name), rep);
}

// Each fragment's triangles of `mesh`: first the owned[k] whose centre lies on fragment k's
// stretch of the path, then the other fragments' within the overlap of k.
std::vector<std::vector<uint32_t>> FragmentFaces(const RoadSplitOptions& o, const Plan& p,
                                                 const Mesh& mesh, std::vector<size_t>& owned) {
  const size_t n = p.fragments.size();
  std::vector<std::vector<uint32_t>> own(n), near(n);
  for (uint32_t f = 0; f < mesh.faces.size(); ++f) {
    const auto& t = mesh.faces[f];
    const Eigen::Vector3d c =
        (mesh.vertices[t[0]] + mesh.vertices[t[1]] + mesh.vertices[t[2]]) / 3.0;
    const double s = p.path->Locate(c).s;
    const size_t k = FragmentAt(p, s);
    own[k].push_back(f);
    for (size_t j : FragmentsNear(p, s, o.overlap))
      if (j != k) near[j].push_back(f);
  }
  owned.resize(n);
  for (size_t k = 0; k < n; ++k) {
    owned[k] = own[k].size();
    own[k].insert(own[k].end(), near[k].begin(), near[k].end());
  }
  return own;
}

// dynmask's kept mesh (dynmask-mesh.ply: the scene as recorded, vehicles and all) split as
// mesh.ply is, so that dynmask on a fragment judges against it, not against the fragment's
// mesh.ply, which a road build made without the masked pixels.
void SplitDynmaskMesh(const RoadSplitOptions& o, const Workspace& ws, const fs::path& tmp,
                      const Plan& p) {
  if (!fs::exists(ws.DynmaskMeshPath())) return;
  const Mesh mesh = ReadMesh(ws.DynmaskMeshPath().string());
  std::vector<size_t> owned;
  const auto faces = FragmentFaces(o, p, mesh, owned);
  for (size_t k = 0; k < p.fragments.size(); ++k) {
    if (faces[k].empty()) continue;
    const Workspace dst(tmp / "Models" / p.fragments[k].id);
    WriteMesh(dst.DynmaskMeshPath().string(), SubMesh(mesh, faces[k]));
  }
}

// Each fragment's mesh: its own triangles first, then its neighbours' within the overlap.
void SplitMesh(const RoadSplitOptions& o, const Workspace& ws, const fs::path& tmp, Plan& p,
               RoadSplitReport& rep) {
  if (!fs::exists(ws.MeshPath())) return;
  const Mesh mesh = ReadMesh(ws.MeshPath().string());
  rep.triangles = mesh.faces.size();
  std::vector<size_t> owned;
  const auto faces = FragmentFaces(o, p, mesh, owned);
  for (size_t k = 0; k < p.fragments.size(); ++k) {
    const Mesh out = SubMesh(mesh, faces[k]);
    p.fragments[k].owned_faces = owned[k];
    p.fragments[k].mesh_faces = out.faces.size();
    p.fragments[k].mesh_vertices = out.vertices.size();
    if (owned[k] > 0) {
      std::array<Eigen::Vector3d, 2> box{out.vertices[0], out.vertices[0]};
      for (size_t f = 0; f < owned[k]; ++f)
        for (uint32_t v : out.faces[f])
          box[0] = box[0].cwiseMin(out.vertices[v]), box[1] = box[1].cwiseMax(out.vertices[v]);
      p.fragments[k].bounds = box;
    }
    if (out.faces.empty()) continue;
    const Workspace dst(tmp / "Models" / p.fragments[k].id);
    WriteMesh((dst.root() / "mesh.ply").string(), out);
  }
}

// The workspace's records every fragment keeps: its georeference (georef.json) and how its mesh
// was made (roadmesh's record), which say whether it is metric (drive, simulate).
std::vector<fs::path> WorkspaceRecords(const Workspace& ws) {
  std::vector<fs::path> out;
  for (const fs::path& p : {ws.root() / "georef.json", ws.root() / "provenance" / "roadmesh.json"})
    if (fs::is_regular_file(p)) out.push_back(p);
  return out;
}

void WriteFragments(const RoadSplitOptions& o, const Workspace& ws, const Reconstruction& rec,
                    const std::vector<const ImageRecord*>& images, const fs::path& tmp, Plan& p,
                    RoadSplitReport& rep) {
  const std::vector<fs::path> records = WorkspaceRecords(ws);
  std::map<std::string, ExposureRow> exposure;
  if (fs::exists(ws.ExposurePath()))
    for (auto& row : ReadExposureTsv(ws.ExposurePath().string())) exposure[row.image] = row;
  for (size_t k = 0; k < p.fragments.size(); ++k) {
    RoadFragment& f = p.fragments[k];
    f.dir = tmp / "Models" / f.id;
    const Workspace dst(f.dir);
    CreateFolder(dst.SparseDir());
    WriteColmapText(SubModel(rec, images, p.members[k]), dst.SparseDir().string());
    std::vector<ExposureRow> rows;
    for (size_t i : p.members[k]) {
      LinkImageFiles(ws, dst, images[i]->name, rep);
      auto it = exposure.find(images[i]->name);
      if (it != exposure.end()) rows.push_back(it->second);
      if (p.owner[i] == k) f.owned_images.push_back(images[i]->name);
    }
    if (!rows.empty()) WriteExposureTsv(dst.ExposurePath().string(), rows);
    RoadSplitReport records_linked;  // (rep counts per-image files)
    for (const fs::path& r : records)
      LinkFile(r, dst.root() / r.lexically_relative(ws.root()), records_linked);
    f.s_begin = p.bounds[k];
    f.s_end = p.bounds[k + 1];
    f.overlap = o.overlap;
  }
  SplitMesh(o, ws, tmp, p, rep);
  SplitDynmaskMesh(o, ws, tmp, p);
  WriteRoadGraph(tmp, p.fragments);
  RoadPath path{PathStep(o), {}, {}};  // what RoadMeshes re-owns a fragment's new mesh by
  for (const ImageRecord* im : p.record) {
    path.names.push_back(im->name);
    path.centres.push_back(im->world_to_camera.Centre());
  }
  WriteRoadPath(tmp, path);
  for (RoadFragment& f : p.fragments) WriteFragmentRecord(f);
}

// Every file the road is made from: the model, the mesh, exposure.tsv and each image's files.
std::vector<fs::path> RoadInputs(const Workspace& ws,
                                 const std::vector<const ImageRecord*>& images) {
  std::vector<fs::path> in = ws.SparseModelFiles();
  in.push_back(ws.MeshPath());
  if (fs::exists(ws.DynmaskMeshPath())) in.push_back(ws.DynmaskMeshPath());
  in.push_back(ws.ExposurePath());
  for (fs::path& r : WorkspaceRecords(ws)) in.push_back(std::move(r));
  for (const ImageRecord* im : images) {
    const std::string& n = im->name;
    for (const fs::path& f :
         {ws.ImagePath(n), ws.TexturePath(n), ws.MaskPath(n), ws.LabelPath(n), ws.DynamicPath(n),
          ws.DepthPath(n), ws.StereoDepthPath(n), ws.StereoConfidencePath(n)})
      if (fs::exists(f)) in.push_back(f);
  }
  return in;
}

// Rethrows the exception being handled. An Error naming a file of the road under construction
// (inside `tmp`, gone by now) names it where the road would have it: ROAD/...
[[noreturn]] void RethrowNamedInRoad(const fs::path& tmp, const fs::path& road) {
  try {
    throw;
  } catch (const UsageError&) {
    throw;
  } catch (const Error& e) {
    const std::string built = tmp.string(), file = e.file();
    if (file.compare(0, built.size(), built) != 0) throw;
    const fs::path rel = fs::path(file).lexically_relative(tmp);
    throw Error((rel == "." ? road : road / rel).string(), e.line(),
                std::string(e.what()).substr(Located(file, e.line(), "").size()));
  }
}

}  // namespace

RoadSplitReport RunRoadSplit(const RoadSplitOptions& o) {
  o.Check();
  fs::path road = fs::path(o.road).lexically_normal();
  if (road.filename().empty()) road = road.parent_path();  // "road/"
  const Workspace ws(o.workspace);
  ws.Require("roadsplit", {WsItem::kSparse});
  const Reconstruction rec = ReadColmapModel(ws.SparseDir().string());
  const std::vector<const ImageRecord*> images = rec.ImagesByName();
  FinishInterruptedWrites(ws.StereoDir());  // the inputs judged as the links will be
  RoadSplitOptions resolved = o;
  const OptionTable table = DeclareOptions(resolved);
  Ledger ledger(road, "roadsplit", table, RoadInputs(ws, images), ws.root());
  const fs::path graph = Road::GraphPathOf(road);
  RoadSplitReport rep;
  rep.why = ledger.Stale(graph, {}, o.force);
  if (rep.why.empty()) {
    rep.up_to_date = true;
    return rep;
  }
  if (fs::exists(road) && !fs::is_empty(road) && !fs::exists(graph))
    throw UsageError(o.road + ": exists and is not a road (remove it or name another folder)");
  Plan p;
  PlanPath(o, images, p);
  AssignImages(o, images, p);
  for (size_t k = 0; k + 1 < p.bounds.size(); ++k) {
    RoadFragment f;
    f.id = p.seq + "/" + FragmentName(k);
    p.fragments.push_back(f);
  }
  rep.junctions = LinkFragments(o, images, p);
  rep.fragments = p.fragments.size();
  rep.images = images.size();
  rep.path_length = p.path->Length();
  rep.fragment_length = p.bounds[1] - p.bounds[0];
  // Built under a temporary name beside ROAD (a dead run's leftover goes first), renamed when
  // complete.
  const fs::path parent = road.parent_path().empty() ? fs::path(".") : road.parent_path();
  RemoveStaleTemporaries(parent);
  const fs::path tmp = TemporaryPathFor(parent / road.filename());
  try {
    CreateFolder(tmp);
    WriteFragments(o, ws, rec, images, tmp, p, rep);
    ReplaceFolder(tmp, road);  // linked and copied files synced too, then one exchange
    ledger.Done(graph);
    ledger.Write({{"fragments", rep.fragments}, {"junctions", rep.junctions}});
  } catch (...) {
    std::error_code ec;
    fs::remove_all(tmp, ec);
    RethrowNamedInRoad(tmp, road);
  }
  return rep;
}

}  // namespace mvtm
