#include "scene/mesh.h"

#include <Eigen/Geometry>
#include <limits>

namespace mvtm {

void Mesh::ComputeNormals() {
  normals.assign(vertices.size(), Eigen::Vector3f::Zero());
  std::vector<Eigen::Vector3d> acc(vertices.size(), Eigen::Vector3d::Zero());
  for (const auto& f : faces) {
    Eigen::Vector3d n = (vertices[f[1]] - vertices[f[0]]).cross(vertices[f[2]] - vertices[f[0]]);
    for (uint32_t v : f) acc[v] += n;  // |n| = 2·area: area weighting
  }
  for (size_t i = 0; i < acc.size(); ++i) {
    double len = acc[i].norm();
    normals[i] = len > 0 ? Eigen::Vector3f((acc[i] / len).cast<float>()) : Eigen::Vector3f(0, 0, 1);
  }
}

void Mesh::Bounds(Eigen::Vector3d& lo, Eigen::Vector3d& hi) const {
  lo.setConstant(std::numeric_limits<double>::infinity());
  hi.setConstant(-std::numeric_limits<double>::infinity());
  for (const auto& v : vertices) {
    lo = lo.cwiseMin(v);
    hi = hi.cwiseMax(v);
  }
}

Mesh SubMesh(const Mesh& m, const std::vector<uint32_t>& faces) {
  Mesh out;
  std::vector<int64_t> remap(m.vertices.size(), -1);
  for (uint32_t f : faces) {
    std::array<uint32_t, 3> t{};
    for (int k = 0; k < 3; ++k) {
      const uint32_t v = m.faces[f][static_cast<size_t>(k)];
      if (remap[v] < 0) {
        remap[v] = static_cast<int64_t>(out.vertices.size());
        out.vertices.push_back(m.vertices[v]);
        if (m.has_normals()) out.normals.push_back(m.normals[v]);
        if (m.has_colors()) out.colors.push_back(m.colors[v]);
      }
      t[static_cast<size_t>(k)] = static_cast<uint32_t>(remap[v]);
    }
    out.faces.push_back(t);
    if (m.has_face_kinds()) out.face_kinds.push_back(m.face_kinds[f]);
  }
  return out;
}

}  // namespace mvtm
