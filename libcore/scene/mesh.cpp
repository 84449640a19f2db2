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

}  // namespace mvtm
