// mvtm — the meshes of a road's fragments, streamed (thesis Appendix D.3): each fragment's own
// triangles (the first owned_faces of its mesh.ply, workspace/road.h), read on demand or ahead
// on a second thread, kept while resident and dropped after. A fragment whose mesh.ply was made
// anew after the split (its PLY header's counts are not fragment.json's mesh_faces and
// mesh_vertices: say roadmesh --dense run on the fragment) owns the triangles of its mesh whose
// centroid lies over its own stretch of the path of record (ROAD/path.txt), as roadsplit
// assigns them: the fragments' new meshes meet at the stretch boundaries.
//
// Thread safety: one thread calls the methods; the reads run on std::async threads.
#pragma once

#include <future>
#include <map>
#include <memory>
#include <mutex>
#include <vector>

#include "scene/mesh.h"
#include "workspace/road.h"

namespace mvtm {

class PathIndex;

class RoadMeshes {
 public:
  explicit RoadMeshes(const Road& road);
  ~RoadMeshes();

  // Starts reading the fragments `ks` that are not held yet.
  void Prefetch(const std::vector<size_t>& ks);
  // The union of the own triangles of the fragments `ks` (read now unless prefetched), in that
  // order; the fragments `next` (those resident next) start reading on second threads, and
  // every other held fragment is dropped. Colours and normals are kept when every part with
  // triangles has them. Throws Error for an unreadable mesh or an owned_faces beyond its
  // triangles.
  Mesh Union(const std::vector<size_t>& ks, const std::vector<size_t>& next);
  // True when fragment k's mesh.ply is the one roadsplit wrote (its PLY header's triangle and
  // vertex counts are fragment.json's, or the record has none): its first owned_faces are its
  // own and its bounds hold. (A copy that is not is re-owned by the same rule: no harm.)
  bool AsSplit(size_t k) const;
  // Fragments held now (read or being read).
  size_t held() const { return held_.size(); }

 private:
  std::shared_ptr<const Mesh> Own(size_t k) const;
  // The path of record (ROAD/path.txt), read on first use (from any thread).
  const PathIndex& Path() const;

  const Road& road_;
  mutable std::once_flag path_once_;
  mutable std::unique_ptr<PathIndex> path_;
  std::map<size_t, std::shared_future<std::shared_ptr<const Mesh>>> held_;
};

}  // namespace mvtm
