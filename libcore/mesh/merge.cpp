#include "mesh/merge.h"

#include <Eigen/Geometry>
#include <cmath>
#include <map>

#include "base/error.h"

namespace mvtm {

Mesh MergeProxyBehind(const Mesh& dense, const Mesh& proxy, const Eigen::Vector3d& up,
                      double ground_below, double walls_behind, MergeReport* report) {
  if (!(ground_below >= 0) || !std::isfinite(ground_below) || !std::isfinite(walls_behind))
    throw Error("merge: the offsets must be finite lengths, ground_below >= 0");
  if (!(up.norm() > 0)) throw Error("merge: the up direction is zero");
  if (walls_behind > 0 && !proxy.has_normals())
    throw Error("merge: the proxy has no vertex normals");
  const Eigen::Vector3d u = up.normalized();
  Mesh out;
  out.vertices = dense.vertices;
  out.faces = dense.faces;
  std::map<uint32_t, uint32_t> index;  // proxy vertex → output vertex (shared within a part)
  auto vertex = [&](uint32_t v, bool ground) {
    auto it = index.find(v);
    if (it != index.end()) return it->second;
    const Eigen::Vector3d shift =
        ground ? Eigen::Vector3d(-ground_below * u)
               : Eigen::Vector3d(-walls_behind * proxy.normals[v].cast<double>());
    out.vertices.push_back(proxy.vertices[v] + shift);
    return index[v] = static_cast<uint32_t>(out.vertices.size() - 1);
  };
  MergeReport r;
  for (const auto& f : proxy.faces) {
    const Eigen::Vector3d n = (proxy.vertices[f[1]] - proxy.vertices[f[0]])
                                  .cross(proxy.vertices[f[2]] - proxy.vertices[f[0]]);
    if (n.norm() == 0) continue;
    const bool ground = n.normalized().dot(u) >= std::cos(M_PI / 4);
    if (!ground && walls_behind < 0) continue;
    out.faces.push_back({vertex(f[0], ground), vertex(f[1], ground), vertex(f[2], ground)});
    ++(ground ? r.ground_faces : r.wall_faces);
  }
  out.ComputeNormals();
  if (report) *report = r;
  return out;
}

}  // namespace mvtm
