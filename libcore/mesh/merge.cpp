#include "mesh/merge.h"

#include <Eigen/Geometry>
#include <cmath>
#include <map>

#include "base/error.h"

namespace mvtm {

Mesh MergeGroundBeneath(const Mesh& dense, const Mesh& proxy, const Eigen::Vector3d& up,
                        double depth_below, MergeReport* report) {
  if (!(depth_below >= 0) || !std::isfinite(depth_below))
    throw Error("merge: depth_below must be a length >= 0");
  if (!(up.norm() > 0)) throw Error("merge: the up direction is zero");
  const Eigen::Vector3d u = up.normalized();
  Mesh out;
  out.vertices = dense.vertices;
  out.faces = dense.faces;
  std::map<uint32_t, uint32_t> index;  // proxy vertex → output vertex (ground vertices are shared)
  auto vertex = [&](uint32_t v) {
    auto it = index.find(v);
    if (it != index.end()) return it->second;
    out.vertices.push_back(proxy.vertices[v] - depth_below * u);
    return index[v] = static_cast<uint32_t>(out.vertices.size() - 1);
  };
  size_t kept = 0;
  for (const auto& f : proxy.faces) {
    const Eigen::Vector3d n = (proxy.vertices[f[1]] - proxy.vertices[f[0]])
                                  .cross(proxy.vertices[f[2]] - proxy.vertices[f[0]]);
    if (n.norm() == 0 || n.normalized().dot(u) < std::cos(M_PI / 4)) continue;  // not ground
    out.faces.push_back({vertex(f[0]), vertex(f[1]), vertex(f[2])});
    ++kept;
  }
  out.ComputeNormals();
  if (report) report->proxy_faces_kept = kept;
  return out;
}

}  // namespace mvtm
