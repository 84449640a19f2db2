#include "mesh/merge.h"

#include <Eigen/Geometry>
#include <algorithm>
#include <array>
#include <cmath>
#include <map>
#include <set>
#include <unordered_map>
#include <vector>

#include "base/error.h"
#include "base/stats.h"

namespace mvtm {

namespace {

Eigen::Vector3d FaceNormal(const Mesh& m, const std::array<uint32_t, 3>& f) {
  return (m.vertices[f[1]] - m.vertices[f[0]]).cross(m.vertices[f[2]] - m.vertices[f[0]]);
}

Eigen::Vector3d Centroid(const Mesh& m, const std::array<uint32_t, 3>& f) {
  return (m.vertices[f[0]] + m.vertices[f[1]] + m.vertices[f[2]]) / 3.0;
}

// A proxy face is ground when its (non-zero) normal is within 45° of up.
bool IsProxyGround(const Eigen::Vector3d& n, const Eigen::Vector3d& u) {
  return n.norm() > 0 && n.normalized().dot(u) >= std::cos(M_PI / 4);
}

}  // namespace

double ProxyGroundAbove(const Mesh& dense, const Mesh& proxy, const Eigen::Vector3d& up,
                        double reach, double bound) {
  if (!(up.norm() > 0) || !(reach > 0) || !(bound > 0))
    throw Error("merge: the up direction, reach and bound must be non-zero");
  const Eigen::Vector3d u = up.normalized();
  const Eigen::Vector3d e1 = u.unitOrthogonal(), e2 = u.cross(e1);
  // The proxy's ground face centroids in cells of `reach` across `up`; coordinates relative to
  // the first vertex, so a road at UTM coordinates keeps its precision.
  const Eigen::Vector3d o = proxy.vertices.empty() ? Eigen::Vector3d::Zero() : proxy.vertices[0];
  auto index = [&](double a) { return static_cast<int64_t>(std::floor(a / reach)); };
  auto key = [](int64_t ia, int64_t ib) {  // unsigned: no shift of a negative value
    return (static_cast<uint64_t>(static_cast<uint32_t>(static_cast<int32_t>(ia))) << 32) |
           static_cast<uint32_t>(static_cast<int32_t>(ib));
  };
  std::unordered_map<uint64_t, std::vector<Eigen::Vector3d>> grid;  // (a, b, height)
  for (const auto& f : proxy.faces) {
    if (!IsProxyGround(FaceNormal(proxy, f), u)) continue;
    const Eigen::Vector3d c = Centroid(proxy, f) - o;
    grid[key(index(c.dot(e1)), index(c.dot(e2)))].push_back({c.dot(e1), c.dot(e2), c.dot(u)});
  }
  std::vector<double> h;
  for (const auto& f : dense.faces) {
    const Eigen::Vector3d n = FaceNormal(dense, f);
    if (!(n.norm() > 0) || std::abs(n.normalized().dot(u)) < std::cos(M_PI / 6)) continue;
    const Eigen::Vector3d c = Centroid(dense, f) - o;
    const double a = c.dot(e1), b = c.dot(e2);
    const int64_t ia = index(a), ib = index(b);
    double best = reach * reach, height = 0;
    bool found = false;
    for (int64_t i = -1; i <= 1; ++i)
      for (int64_t j = -1; j <= 1; ++j) {
        auto it = grid.find(key(ia + i, ib + j));
        if (it == grid.end()) continue;
        for (const Eigen::Vector3d& p : it->second) {
          const double d2 = (p.x() - a) * (p.x() - a) + (p.y() - b) * (p.y() - b);
          if (d2 <= best) best = d2, height = p.z(), found = true;
        }
      }
    const double above = height - c.dot(u);
    if (found && std::abs(above) <= bound) h.push_back(above);
  }
  return h.size() < 50 ? 0.0 : Median(std::move(h));
}

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
    const Eigen::Vector3d n = FaceNormal(proxy, f);
    if (n.norm() > 0) kind[i] = IsProxyGround(n, u) ? 2 : 1;
    if (kind[i] == 2 && (walls_behind > 0 || (walls_behind >= 0 && ground_below > 0)))
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
    if (!ground && ground_points.count(key(v)))  // the wall's foot: as far down as either went
      shift -= std::max(walls_behind, ground_below) * u;
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
