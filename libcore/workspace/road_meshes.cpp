#include "workspace/road_meshes.h"

#include <algorithm>
#include <fstream>
#include <string>

#include "base/error.h"
#include "index/path_index.h"
#include "io/mesh_io.h"
#include "workspace/workspace.h"

namespace mvtm {

RoadMeshes::RoadMeshes(const Road& road) : road_(road) {}

RoadMeshes::~RoadMeshes() {
  held_.clear();  // (the reads use path_)
}

const PathIndex& RoadMeshes::Path() const {
  std::call_once(path_once_, [this] {
    const RoadPath p = ReadRoadPath(road_.root());
    path_ = std::make_unique<PathIndex>(p.centres, p.step);
  });
  return *path_;
}

namespace {

// The vertex and face counts a PLY header declares ("element vertex N", "element face N"; -1
// for one it does not declare).
std::pair<long, long> PlyCounts(const fs::path& path) {
  std::ifstream in(path, std::ios::binary);
  std::pair<long, long> n{-1, -1};
  for (std::string line; std::getline(in, line) && line.rfind("end_header", 0) != 0;) {
    if (line.rfind("element vertex ", 0) == 0) n.first = std::atol(line.c_str() + 15);
    if (line.rfind("element face ", 0) == 0) n.second = std::atol(line.c_str() + 13);
  }
  return n;
}

}  // namespace

bool RoadMeshes::AsSplit(size_t k) const {
  const RoadFragment& f = road_.fragments()[k];
  if (!f.mesh_faces) return true;
  const auto [vertices, faces] = PlyCounts(Workspace(f.dir).MeshPath());
  return faces == static_cast<long>(*f.mesh_faces) &&
         (!f.mesh_vertices || vertices == static_cast<long>(*f.mesh_vertices));
}

void RoadMeshes::Prefetch(const std::vector<size_t>& ks) {
  for (size_t k : ks)
    if (!held_.count(k))
      held_[k] = std::async(std::launch::async, [this, k] { return Own(k); }).share();
}

Mesh RoadMeshes::Union(const std::vector<size_t>& ks, const std::vector<size_t>& next) {
  Prefetch(ks);
  Prefetch(next);
  auto listed = [](const std::vector<size_t>& v, size_t k) {
    return std::find(v.begin(), v.end(), k) != v.end();
  };
  for (auto it = held_.begin(); it != held_.end();)
    if (!listed(ks, it->first) && !listed(next, it->first))
      it = held_.erase(it);
    else
      ++it;
  std::vector<std::shared_ptr<const Mesh>> parts;
  bool colours = true, normals = true;
  for (size_t k : ks) {
    parts.push_back(held_.at(k).get());
    const Mesh& m = *parts.back();
    colours = colours && (m.faces.empty() || m.has_colors());
    normals = normals && (m.faces.empty() || m.has_normals());
  }
  Mesh out;
  for (const auto& m : parts) {
    if (m->faces.empty()) continue;
    const auto base = static_cast<uint32_t>(out.vertices.size());
    out.vertices.insert(out.vertices.end(), m->vertices.begin(), m->vertices.end());
    if (colours) out.colors.insert(out.colors.end(), m->colors.begin(), m->colors.end());
    if (normals) out.normals.insert(out.normals.end(), m->normals.begin(), m->normals.end());
    for (const auto& f : m->faces) out.faces.push_back({f[0] + base, f[1] + base, f[2] + base});
  }
  return out;
}

std::shared_ptr<const Mesh> RoadMeshes::Own(size_t k) const {
  const RoadFragment& f = road_.fragments()[k];
  auto m = std::make_shared<Mesh>();
  const Workspace ws(f.dir);
  if (f.owned_faces == 0 && !fs::exists(ws.MeshPath())) return m;
  *m = ReadMesh(ws.MeshPath().string());
  if (!AsSplit(k)) {
    // Made anew in the fragment: its own triangles are those over its stretch of the path.
    const PathIndex& path = Path();
    std::vector<uint32_t> own;
    for (uint32_t i = 0; i < m->faces.size(); ++i) {
      const auto& t = m->faces[i];
      const Eigen::Vector3d c = (m->vertices[t[0]] + m->vertices[t[1]] + m->vertices[t[2]]) / 3;
      if (road_.FragmentAt(path.Locate(c).s) == k) own.push_back(i);
    }
    *m = SubMesh(*m, own);
    return m;
  }
  if (m->faces.size() < f.owned_faces)
    throw Error(Road::RecordPath(f.dir).string(), 0,
                "owned_faces " + std::to_string(f.owned_faces) + " exceeds the " +
                    std::to_string(m->faces.size()) + " triangles of " + ws.MeshPath().string());
  m->faces.resize(f.owned_faces);
  return m;
}

}  // namespace mvtm
