#include "workspace/road_meshes.h"

#include <algorithm>

#include "base/error.h"
#include "io/mesh_io.h"
#include "workspace/workspace.h"

namespace mvtm {

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
  if (f.owned_faces == 0) return m;
  const Workspace ws(f.dir);
  *m = ReadMesh(ws.MeshPath().string());
  if (f.mesh_faces && m->faces.size() != *f.mesh_faces)
    throw Error(ws.MeshPath().string(), 0,
                "has " + std::to_string(m->faces.size()) + " triangles, not the " +
                    std::to_string(*f.mesh_faces) +
                    " roadsplit wrote: the mesh was replaced after the split (its first " +
                    "owned_faces are no longer the fragment's own); split the workspace again");
  if (m->faces.size() < f.owned_faces)
    throw Error(Road::RecordPath(f.dir).string(), 0,
                "owned_faces " + std::to_string(f.owned_faces) + " exceeds the " +
                    std::to_string(m->faces.size()) + " triangles of " + ws.MeshPath().string());
  m->faces.resize(f.owned_faces);
  return m;
}

}  // namespace mvtm
