#include "workspace/road.h"

#include <algorithm>
#include <fstream>
#include <map>
#include <nlohmann/json.hpp>
#include <set>

#include "base/atomic_file.h"
#include "base/error.h"
#include "base/text.h"
#include "io/colmap_model.h"
#include "workspace/workspace.h"

namespace mvtm {

namespace {

// The image names of a workspace's model.
std::set<std::string> ModelImageNames(const fs::path& sparse) {
  const std::vector<std::string> names = ReadColmapImageNames(sparse.string());
  return {names.begin(), names.end()};
}

void ReadRecord(RoadFragment& f) {
  const fs::path p = Road::RecordPath(f.dir);
  std::ifstream in(p, std::ios::binary);
  if (!in) throw Error(p.string(), 0, "cannot open (every fragment of a road has one)");
  const nlohmann::json j = nlohmann::json::parse(in, nullptr, false);
  auto bad = [&](const std::string& what) { throw Error(p.string(), 0, what); };
  if (j.is_discarded() || !j.is_object()) bad("not a JSON object");
  if (!j.contains("images") || !j["images"].is_array()) bad("\"images\" must be an array of names");
  for (const auto& n : j["images"]) {
    if (!n.is_string()) bad("\"images\" must be an array of names");
    f.owned_images.push_back(n.get<std::string>());
  }
  if (!j.contains("owned_faces") || !j["owned_faces"].is_number_unsigned())
    bad("\"owned_faces\" must be a count");
  f.owned_faces = j["owned_faces"].get<size_t>();
  if (!j.contains("s") || !j["s"].is_array() || j["s"].size() != 2 || !j["s"][0].is_number() ||
      !j["s"][1].is_number())
    bad("\"s\" must be [BEGIN, END] in metres");
  f.s_begin = j["s"][0].get<double>();
  f.s_end = j["s"][1].get<double>();
  if (j.contains("overlap") && !j["overlap"].is_number()) bad("\"overlap\" must be metres");
  f.overlap = j.value("overlap", 0.0);
  auto count = [&](const char* key, std::optional<size_t>& field) {
    if (!j.contains(key)) return;
    if (!j[key].is_number_unsigned()) bad(std::string("\"") + key + "\" must be a count");
    field = j[key].get<size_t>();
  };
  count("mesh_faces", f.mesh_faces);
  count("mesh_vertices", f.mesh_vertices);
  if (!j.contains("bounds")) return;
  const nlohmann::json& b = j["bounds"];
  std::array<Eigen::Vector3d, 2> box;
  for (int k = 0; k < 2; ++k)
    for (int a = 0; a < 3; ++a) {
      if (!b.is_array() || b.size() != 2 || !b[k].is_array() || b[k].size() != 3 ||
          !b[k][a].is_number())
        bad("\"bounds\" must be [[XMIN, YMIN, ZMIN], [XMAX, YMAX, ZMAX]]");
      box[k][a] = b[k][a].get<double>();
    }
  if (!(box[0].array() <= box[1].array()).all()) bad("\"bounds\": a minimum above its maximum");
  f.bounds = box;
}

}  // namespace

bool Road::IsRoad(const fs::path& dir) { return fs::is_regular_file(GraphPathOf(dir)); }

Road::Road(fs::path root) : root_(std::move(root)) {
  const fs::path graph = GraphPathOf(root_);
  LineReader r(graph.string());
  // First pass: the nodes (so a neighbour may be named before its own line).
  struct Line {
    long no;
    std::vector<std::string> tokens;
  };
  std::vector<Line> lines;
  std::map<std::string, size_t> index;
  for (std::string line; r.Next(line);) {
    Line l{r.line(), {}};
    for (auto t : SplitBlank(line)) l.tokens.emplace_back(t);
    if (l.tokens.size() % 2 != 1)
      r.Fail("expected NODE then NEIGHBOUR POSE pairs, found " + std::to_string(l.tokens.size()) +
             " fields");
    RoadFragment f;
    f.id = l.tokens[0];
    f.dir = FragmentDir(root_, f.id);
    if (!index.emplace(f.id, fragments_.size()).second) r.Fail(f.id + ": named twice as a node");
    fragments_.push_back(std::move(f));
    lines.push_back(std::move(l));
  }
  if (fragments_.empty()) throw Error(graph.string(), 0, "the graph has no fragments");
  auto fail = [&](long no, const std::string& what) { throw Error(graph.string(), no, what); };
  std::vector<std::set<std::string>> names(fragments_.size());
  for (size_t i = 0; i < fragments_.size(); ++i) {
    RoadFragment& f = fragments_[i];
    const Workspace ws(f.dir);
    if (!fs::is_directory(f.dir) || !HasColmapModel(ws.SparseDir().string()))
      fail(lines[i].no, f.id + ": no fragment workspace at " + f.dir.string());
    ReadRecord(f);
    names[i] = ModelImageNames(ws.SparseDir());
    for (const std::string& n : f.owned_images)
      if (!names[i].count(n))
        throw Error(RecordPath(f.dir).string(), 0, n + ": owned but not in the fragment's model");
  }
  for (size_t i = 0; i < fragments_.size(); ++i) {
    const Line& l = lines[i];
    for (size_t k = 1; k + 1 < l.tokens.size(); k += 2) {
      auto it = index.find(l.tokens[k]);
      if (it == index.end()) fail(l.no, l.tokens[k] + ": not a fragment of the graph");
      if (it->second == i) fail(l.no, l.tokens[k] + ": a fragment cannot neighbour itself");
      const std::string& pose = l.tokens[k + 1];
      if (!names[i].count(pose) || !names[it->second].count(pose))
        fail(l.no, pose + ": not an image of both " + fragments_[i].id + " and " + l.tokens[k]);
      fragments_[i].links.push_back({it->second, pose});
    }
  }
  for (size_t i = 0; i < fragments_.size(); ++i)
    for (const RoadLink& link : fragments_[i].links)
      if (!Adjacent(link.to, i))
        fail(lines[i].no, fragments_[link.to].id + " does not list " + fragments_[i].id +
                              " back (links are mutual)");
}

size_t Road::FragmentAt(double s) const {
  size_t k = 0;
  while (k + 1 < fragments_.size() && s >= fragments_[k + 1].s_begin) ++k;
  return k;
}

bool Road::Adjacent(size_t a, size_t b) const {
  for (const RoadLink& l : fragments_[a].links)
    if (l.to == b) return true;
  return false;
}

std::vector<fs::path> Road::ResidentFiles(size_t home) const {
  std::vector<fs::path> out{PathFileOf(root_)};  // which triangles of a new mesh are own
  for (size_t k : Resident(home)) {
    out.push_back(Workspace(fragments_[k].dir).MeshPath());
    out.push_back(RecordPath(fragments_[k].dir));
  }
  return out;
}

std::vector<std::pair<size_t, std::string>> Road::RecordedFrames() const {
  std::vector<std::pair<size_t, std::string>> out;
  for (size_t k = 0; k < fragments_.size(); ++k)
    for (const std::string& n : fragments_[k].owned_images) out.emplace_back(k, n);
  return out;
}

std::vector<size_t> Road::Resident(size_t home) const {
  std::vector<size_t> out{home};
  for (const RoadLink& l : fragments_[home].links)
    if (std::find(out.begin(), out.end(), l.to) == out.end()) out.push_back(l.to);
  return out;
}

void WriteRoadGraph(const fs::path& root, const std::vector<RoadFragment>& fragments) {
  WriteTextAtomic(Road::GraphPathOf(root), [&](std::ostream& s) {
    s << "# mvtm road graph (man 5 mvtm-workspace): NODE then NEIGHBOUR POSE pairs\n";
    for (const RoadFragment& f : fragments) {
      s << f.id;
      for (const RoadLink& l : f.links) s << ' ' << fragments[l.to].id << ' ' << l.pose;
      s << '\n';
    }
  });
}

void WriteRoadPath(const fs::path& root, const RoadPath& path) {
  WriteTextAtomic(Road::PathFileOf(root), [&](std::ostream& s) {
    s << "# mvtm road path of record (man 5 mvtm-workspace): step, then NAME X Y Z in order\n";
    s << "step " << FormatDouble(path.step) << '\n';
    for (size_t i = 0; i < path.names.size(); ++i)
      s << path.names[i] << ' ' << FormatDouble(path.centres[i].x()) << ' '
        << FormatDouble(path.centres[i].y()) << ' ' << FormatDouble(path.centres[i].z()) << '\n';
  });
}

RoadPath ReadRoadPath(const fs::path& root) {
  const fs::path p = Road::PathFileOf(root);
  if (!fs::is_regular_file(p))
    throw Error(p.string(), 0, "missing (a road made by an older roadsplit: split it again)");
  LineReader r(p.string());
  RoadPath path;
  for (std::string line; r.Next(line);) {
    const auto f = SplitBlank(line);
    if (path.step == 0) {
      if (f.size() != 2 || f[0] != "step") r.Fail("expected 'step STEP' first");
      path.step = ParseDouble(f[1], r, "step");
      if (!(path.step > 0)) r.Fail("step must be > 0");
      continue;
    }
    if (f.size() != 4) r.Fail("expected NAME X Y Z, found " + std::to_string(f.size()) + " fields");
    path.names.emplace_back(f[0]);
    path.centres.emplace_back(ParseDouble(f[1], r, "X"), ParseDouble(f[2], r, "Y"),
                              ParseDouble(f[3], r, "Z"));
  }
  if (path.names.size() < 2) throw Error(p.string(), 0, "a path needs two images or more");
  return path;
}

void WriteFragmentRecord(const RoadFragment& f) {
  nlohmann::json j;
  j["images"] = f.owned_images;
  j["owned_faces"] = f.owned_faces;
  j["s"] = {f.s_begin, f.s_end};
  j["overlap"] = f.overlap;
  if (f.mesh_faces) j["mesh_faces"] = *f.mesh_faces;
  if (f.mesh_vertices) j["mesh_vertices"] = *f.mesh_vertices;
  if (f.bounds) {
    const auto& [lo, hi] = *f.bounds;
    j["bounds"] = {{lo.x(), lo.y(), lo.z()}, {hi.x(), hi.y(), hi.z()}};
  }
  WriteTextAtomic(Road::RecordPath(f.dir), [&](std::ostream& s) { s << j.dump(1) << '\n'; });
}

}  // namespace mvtm
