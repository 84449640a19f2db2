#include "mesh/merge.h"

#include <cmath>
#include <unordered_set>

#include "base/error.h"

namespace mvtm {

namespace {

// Integer cell of a point on a grid of `cell` spacing, hashed into 64 bits.
struct CellHash {
  double cell;
  uint64_t Key(const Eigen::Vector3d& p) const {
    const auto c = [&](double v) { return uint64_t(int64_t(std::floor(v / cell)) & 0x1FFFFF); };
    return c(p.x()) << 42 | c(p.y()) << 21 | c(p.z());
  }
};

bool NearDense(const std::unordered_set<uint64_t>& cells, const CellHash& h, const Eigen::Vector3d& p) {
  for (int dx = -1; dx <= 1; ++dx)
    for (int dy = -1; dy <= 1; ++dy)
      for (int dz = -1; dz <= 1; ++dz)
        if (cells.count(h.Key(p + h.cell * Eigen::Vector3d(dx, dy, dz)))) return true;
  return false;
}

}  // namespace

Mesh MergeGroundWhereMissing(const Mesh& dense, const Mesh& proxy, const Eigen::Vector3d& up, double radius,
                             MergeReport* report) {
  if (!(radius > 0) || !std::isfinite(radius)) throw Error("merge: the radius must be a positive length");
  const CellHash h{radius};
  std::unordered_set<uint64_t> cells;
  for (const auto& v : dense.vertices) cells.insert(h.Key(v));
  Mesh out;
  out.vertices = dense.vertices;
  out.faces = dense.faces;
  const Eigen::Vector3d u = up.normalized();
  size_t kept = 0;
  for (const auto& f : proxy.faces) {
    const Eigen::Vector3d a = proxy.vertices[f[0]], b = proxy.vertices[f[1]], c = proxy.vertices[f[2]];
    const Eigen::Vector3d n = (b - a).cross(c - a);
    if (n.norm() == 0 || n.normalized().dot(u) < std::cos(M_PI / 4)) continue;  // not ground
    if (NearDense(cells, h, (a + b + c) / 3.0)) continue;
    const uint32_t base = static_cast<uint32_t>(out.vertices.size());
    out.vertices.insert(out.vertices.end(), {a, b, c});
    out.faces.push_back({base, base + 1, base + 2});
    ++kept;
  }
  out.ComputeNormals();
  if (report) report->proxy_faces_kept = kept;
  return out;
}

}  // namespace mvtm
