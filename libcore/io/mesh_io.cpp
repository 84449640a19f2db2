// PLY through OpenMesh (http://paulbourke.net/dataformats/ply/).
// GCC 12 reports a false maybe-uninitialized inside OpenMesh's property templates.
#pragma GCC diagnostic ignored "-Wmaybe-uninitialized"
#include <OpenMesh/Core/IO/MeshIO.hh>
#include <OpenMesh/Core/Mesh/TriMesh_ArrayKernelT.hh>

#include <filesystem>
#include <limits>

#include "base/atomic_file.h"
#include "base/error.h"
#include "io/mesh_io.h"

namespace mvtm {

namespace {
struct Traits : public OpenMesh::DefaultTraits {
  using Point = OpenMesh::Vec3d;
  using Normal = OpenMesh::Vec3f;
  using Color = OpenMesh::Vec3uc;
  VertexAttributes(OpenMesh::Attributes::Normal | OpenMesh::Attributes::Color);
};
using OMesh = OpenMesh::TriMesh_ArrayKernelT<Traits>;
}  // namespace

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

Mesh ReadMesh(const std::string& path) {
  if (!std::filesystem::exists(path)) throw Error(path, 0, "cannot open");
  OMesh om;
  OpenMesh::IO::Options opt = OpenMesh::IO::Options::VertexColor | OpenMesh::IO::Options::VertexNormal;
  if (!OpenMesh::IO::read_mesh(om, path, opt)) throw Error(path, 0, "cannot read mesh (not a valid PLY/OBJ/OFF?)");
  Mesh m;
  m.vertices.reserve(om.n_vertices());
  for (auto vh : om.vertices()) {
    const auto& p = om.point(vh);
    Eigen::Vector3d v(p[0], p[1], p[2]);
    if (!v.allFinite()) throw Error(path, 0, "vertex " + std::to_string(vh.idx()) + " is not finite");
    m.vertices.push_back(v);
  }
  if (opt.check(OpenMesh::IO::Options::VertexNormal)) {
    for (auto vh : om.vertices()) {
      const auto& n = om.normal(vh);
      m.normals.emplace_back(n[0], n[1], n[2]);
    }
  } else {
    m.missing.push_back("normals");
  }
  if (opt.check(OpenMesh::IO::Options::VertexColor)) {
    for (auto vh : om.vertices()) {
      const auto& c = om.color(vh);
      m.colors.push_back({c[0], c[1], c[2]});
    }
  } else {
    m.missing.push_back("colours");
  }
  for (auto fh : om.faces()) {
    std::array<uint32_t, 3> f{};
    int k = 0;
    for (auto vh : om.fv_range(fh)) {
      if (k < 3) f[k] = static_cast<uint32_t>(vh.idx());
      ++k;
    }
    m.faces.push_back(f);
  }
  if (m.faces.empty()) m.missing.push_back("faces");
  return m;
}

void WriteMesh(const std::string& path, const Mesh& mesh, bool ascii) {
  OMesh om;
  std::vector<OMesh::VertexHandle> vh;
  vh.reserve(mesh.vertices.size());
  for (size_t i = 0; i < mesh.vertices.size(); ++i) {
    const auto& v = mesh.vertices[i];
    vh.push_back(om.add_vertex(OMesh::Point(v.x(), v.y(), v.z())));
    if (mesh.has_normals()) {
      const auto& n = mesh.normals[i];
      om.set_normal(vh.back(), OMesh::Normal(n.x(), n.y(), n.z()));
    }
    if (mesh.has_colors()) {
      const auto& c = mesh.colors[i];
      om.set_color(vh.back(), OMesh::Color(c[0], c[1], c[2]));
    }
  }
  for (const auto& f : mesh.faces) {
    for (uint32_t i : f)
      if (i >= vh.size()) throw Error(path, 0, "face index " + std::to_string(i) + " out of range");
    om.add_face(vh[f[0]], vh[f[1]], vh[f[2]]);
  }
  OpenMesh::IO::Options opt;
  if (!ascii) opt += OpenMesh::IO::Options::Binary;
  if (mesh.has_normals()) opt += OpenMesh::IO::Options::VertexNormal;
  if (mesh.has_colors()) opt += OpenMesh::IO::Options::VertexColor;
  AtomicFile out(path);
  // OpenMesh picks the writer from the extension, so the temporary keeps ".ply".
  if (!OpenMesh::IO::write_mesh(om, out.temp_path().string(), opt, 17))
    throw Error(path, 0, "cannot write mesh");
  out.Commit();
}

}  // namespace mvtm
