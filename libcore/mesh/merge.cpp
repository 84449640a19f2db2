#include "mesh/merge.h"

#include <Eigen/Geometry>
#include <array>
#include <cmath>
#include <map>
#include <set>
#include <vector>

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
  // A wall moved back leaves a gap above the ground's edge through which a ray would see
  // nothing; the wall's foot (its vertices where the ground's edge is) goes down by as much as
  // the wall goes back, which closes the gap for every camera farther from the wall than it is
  // high above the ground (the gap's far side is then at most walls_behind below the ground).
  std::set<std::array<float, 3>> ground_points;
  auto key = [&](uint32_t v) {
    const Eigen::Vector3f p = proxy.vertices[v].cast<float>();
    return std::array<float, 3>{p.x(), p.y(), p.z()};
  };
  // Each proxy face once: 0 degenerate (dropped), 1 wall, 2 ground (normal within 45° of up).
  std::vector<uint8_t> kind(proxy.faces.size(), 0);
  for (size_t i = 0; i < proxy.faces.size(); ++i) {
    const auto& f = proxy.faces[i];
    const Eigen::Vector3d n = (proxy.vertices[f[1]] - proxy.vertices[f[0]])
                                  .cross(proxy.vertices[f[2]] - proxy.vertices[f[0]]);
    if (n.norm() > 0) kind[i] = n.normalized().dot(u) >= std::cos(M_PI / 4) ? 2 : 1;
    if (kind[i] == 2 && walls_behind > 0)
      for (uint32_t v : f) ground_points.insert(key(v));
  }
  Mesh out;
  out.vertices = dense.vertices;
  out.faces = dense.faces;
  std::map<uint32_t, uint32_t> index;  // proxy vertex → output vertex (shared within a part)
  auto vertex = [&](uint32_t v, bool ground) {
    auto it = index.find(v);
    if (it != index.end()) return it->second;
    Eigen::Vector3d shift = ground
                                ? Eigen::Vector3d(-ground_below * u)
                                : Eigen::Vector3d(-walls_behind * proxy.normals[v].cast<double>());
    if (!ground && ground_points.count(key(v))) shift -= walls_behind * u;  // the wall's foot
    out.vertices.push_back(proxy.vertices[v] + shift);
    return index[v] = static_cast<uint32_t>(out.vertices.size() - 1);
  };
  MergeReport r;
  for (size_t i = 0; i < proxy.faces.size(); ++i) {
    const auto& f = proxy.faces[i];
    if (kind[i] == 0) continue;
    const bool ground = kind[i] == 2;
    if (!ground && walls_behind < 0) continue;
    out.faces.push_back({vertex(f[0], ground), vertex(f[1], ground), vertex(f[2], ground)});
    ++(ground ? r.ground_faces : r.wall_faces);
  }
  out.ComputeNormals();
  if (report) *report = r;
  return out;
}

}  // namespace mvtm
