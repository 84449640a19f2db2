// PLY through OpenMesh (http://paulbourke.net/dataformats/ply/).
// GCC 12 reports a false maybe-uninitialized inside OpenMesh's property templates.
#pragma GCC diagnostic ignored "-Wmaybe-uninitialized"
#include "io/mesh_io.h"

#include <Eigen/Geometry>
#include <OpenMesh/Core/IO/MeshIO.hh>
#include <OpenMesh/Core/Mesh/TriMesh_ArrayKernelT.hh>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <limits>
#include <sstream>

#include "base/atomic_file.h"
#include "base/error.h"

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

namespace {

struct PlyProperty {
  std::string name, type, list_count_type;  // list_count_type non-empty for lists
};
struct PlyElement {
  std::string name;
  size_t count = 0;
  std::vector<PlyProperty> props;
};
struct PlyHeader {
  std::string format;
  std::vector<PlyElement> elements;
  bool double_positions = false;
};

// Reads and checks the header. OpenMesh 9's PLY reader loops forever on a header cut before
// "end_header", so every PLY passes through here first.
PlyHeader ReadPlyHeader(std::istream& in, const std::string& path) {
  PlyHeader h;
  std::string line;
  long n = 0;
  size_t bytes = 0;
  while (std::getline(in, line)) {
    ++n;
    bytes += line.size() + 1;
    if (!line.empty() && line.back() == '\r') line.pop_back();
    std::istringstream ls(line);
    std::string key;
    ls >> key;
    if (n == 1 && key != "ply") throw Error(path, 1, "not a PLY file (first line is not 'ply')");
    if (key == "format") {
      ls >> h.format;
    } else if (key == "element") {
      PlyElement e;
      if (!(ls >> e.name >> e.count)) throw Error(path, n, "bad element line");
      h.elements.push_back(e);
    } else if (key == "property") {
      if (h.elements.empty()) throw Error(path, n, "property before any element");
      PlyProperty p;
      ls >> p.type;
      if (p.type == "list") ls >> p.list_count_type >> p.type;
      ls >> p.name;
      if (h.elements.back().name == "vertex" && p.name == "x" &&
          (p.type == "double" || p.type == "float64"))
        h.double_positions = true;
      h.elements.back().props.push_back(p);
    } else if (key == "end_header") {
      if (h.format.empty()) throw Error(path, n, "PLY header has no 'format' line");
      return h;
    }
    if (bytes > 65536) break;
  }
  throw Error(path, n, "PLY header has no 'end_header' (truncated file?)");
}

size_t PlySize(const std::string& t) {
  if (t == "char" || t == "uchar" || t == "int8" || t == "uint8") return 1;
  if (t == "short" || t == "ushort" || t == "int16" || t == "uint16") return 2;
  if (t == "int" || t == "uint" || t == "float" || t == "int32" || t == "uint32" || t == "float32")
    return 4;
  if (t == "double" || t == "float64") return 8;
  return 0;
}

double PlyValue(std::istream& in, const std::string& t, bool ascii, const std::string& path) {
  if (ascii) {
    std::string tok;
    if (!(in >> tok)) throw Error(path, 0, "truncated PLY body");
    try {
      return std::stod(tok);
    } catch (...) {
      throw Error(path, 0, "PLY body: '" + tok + "' is not a number");
    }
  }
  unsigned char b[8];
  size_t n = PlySize(t);
  if (!n) throw Error(path, 0, "unsupported PLY property type '" + t + "'");
  if (!in.read(reinterpret_cast<char*>(b), static_cast<std::streamsize>(n)))
    throw Error(path, 0, "truncated PLY body");
  auto get = [&](auto v) {
    std::memcpy(&v, b, sizeof v);
    return static_cast<double>(v);
  };
  if (t == "char" || t == "int8") return get(int8_t{});
  if (t == "uchar" || t == "uint8") return get(uint8_t{});
  if (t == "short" || t == "int16") return get(int16_t{});
  if (t == "ushort" || t == "uint16") return get(uint16_t{});
  if (t == "int" || t == "int32") return get(int32_t{});
  if (t == "uint" || t == "uint32") return get(uint32_t{});
  if (t == "float" || t == "float32") return get(float{});
  return get(double{});
}

// Double-precision PLY positions, which OpenMesh's reader rounds to float: read directly
// (ascii or binary_little_endian, vertex x y z [nx ny nz] [red green blue], triangle lists).
Mesh ReadPlyDouble(std::istream& in, const PlyHeader& h, const std::string& path) {
  bool ascii = h.format == "ascii";
  if (!ascii && h.format != "binary_little_endian")
    throw Error(path, 0, "PLY format '" + h.format + "' with double positions is not supported");
  Mesh m;
  for (const auto& e : h.elements) {
    bool is_v = e.name == "vertex", is_f = e.name == "face";
    if (is_v) m.vertices.reserve(e.count);
    bool has_n = false, has_c = false;
    for (const auto& p : e.props) {
      has_n |= p.name == "nx";
      has_c |= p.name == "red";
    }
    for (size_t i = 0; i < e.count; ++i) {
      Eigen::Vector3d v(0, 0, 0);
      Eigen::Vector3f nrm(0, 0, 0);
      std::array<uint8_t, 3> col{0, 0, 0};
      for (const auto& p : e.props) {
        if (!p.list_count_type.empty()) {
          size_t cnt = static_cast<size_t>(PlyValue(in, p.list_count_type, ascii, path));
          std::vector<uint32_t> idx(cnt);
          for (auto& x : idx) {
            double d = PlyValue(in, p.type, ascii, path);
            if (d < 0) throw Error(path, 0, "negative face index");
            x = static_cast<uint32_t>(d);
          }
          if (is_f && (p.name == "vertex_indices" || p.name == "vertex_index"))
            for (size_t k = 2; k < cnt; ++k) m.faces.push_back({idx[0], idx[k - 1], idx[k]});
          continue;
        }
        double d = PlyValue(in, p.type, ascii, path);
        if (!is_v) continue;
        if (p.name == "x")
          v.x() = d;
        else if (p.name == "y")
          v.y() = d;
        else if (p.name == "z")
          v.z() = d;
        else if (p.name == "nx")
          nrm.x() = static_cast<float>(d);
        else if (p.name == "ny")
          nrm.y() = static_cast<float>(d);
        else if (p.name == "nz")
          nrm.z() = static_cast<float>(d);
        else if (p.name == "red")
          col[0] = static_cast<uint8_t>(d);
        else if (p.name == "green")
          col[1] = static_cast<uint8_t>(d);
        else if (p.name == "blue")
          col[2] = static_cast<uint8_t>(d);
      }
      if (is_v) {
        if (!v.allFinite()) throw Error(path, 0, "vertex " + std::to_string(i) + " is not finite");
        m.vertices.push_back(v);
        if (has_n) m.normals.push_back(nrm);
        if (has_c) m.colors.push_back(col);
      }
    }
    if (is_v) {
      if (!has_n) m.missing.push_back("normals");
      if (!has_c) m.missing.push_back("colours");
    }
  }
  for (const auto& f : m.faces)
    for (uint32_t i : f)
      if (i >= m.vertices.size())
        throw Error(path, 0, "face index " + std::to_string(i) + " out of range");
  if (m.faces.empty()) m.missing.push_back("faces");
  return m;
}

}  // namespace

Mesh ReadMesh(const std::string& path) {
  if (!std::filesystem::exists(path)) throw Error(path, 0, "cannot open");
  std::string ext = std::filesystem::path(path).extension().string();
  if (ext == ".ply" || ext == ".PLY") {
    std::ifstream in(path, std::ios::binary);
    PlyHeader h = ReadPlyHeader(in, path);
    if (h.double_positions) return ReadPlyDouble(in, h, path);
  }
  omerr().disable();  // OpenMesh's own chatter; failures become Errors below
  omlog().disable();
  OMesh om;
  OpenMesh::IO::Options opt =
      OpenMesh::IO::Options::VertexColor | OpenMesh::IO::Options::VertexNormal;
  if (!OpenMesh::IO::read_mesh(om, path, opt))
    throw Error(path, 0, "cannot read mesh (not a valid PLY/OBJ/OFF?)");
  Mesh m;
  m.vertices.reserve(om.n_vertices());
  for (auto vh : om.vertices()) {
    const auto& p = om.point(vh);
    Eigen::Vector3d v(p[0], p[1], p[2]);
    if (!v.allFinite())
      throw Error(path, 0, "vertex " + std::to_string(vh.idx()) + " is not finite");
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

// Written directly (not through OpenMesh) because OpenMesh 9's PLY writer always stores float32
// positions, which rounds UTM-sized coordinates to 0.5 m. Layout follows COLMAP's meshes:
// x y z [nx ny nz] [red green blue], faces as "list uchar int vertex_indices".
void WriteMesh(const std::string& path, const Mesh& mesh, bool ascii) {
  for (const auto& f : mesh.faces)
    for (uint32_t i : f)
      if (i >= mesh.vertices.size())
        throw Error(path, 0, "face index " + std::to_string(i) + " out of range");
  Eigen::Vector3d lo, hi;
  mesh.Bounds(lo, hi);
  const bool dbl =
      !mesh.vertices.empty() && std::max(lo.cwiseAbs().maxCoeff(), hi.cwiseAbs().maxCoeff()) > 1e5;
  const bool normals = mesh.has_normals(), colours = mesh.has_colors();
  WriteBinaryAtomic(path, [&](std::ostream& o) {
    o << "ply\nformat " << (ascii ? "ascii" : "binary_little_endian") << " 1.0\n"
      << "comment mvtm\nelement vertex " << mesh.vertices.size() << "\n";
    const char* pt = dbl ? "double" : "float";
    o << "property " << pt << " x\nproperty " << pt << " y\nproperty " << pt << " z\n";
    if (normals) o << "property float nx\nproperty float ny\nproperty float nz\n";
    if (colours) o << "property uchar red\nproperty uchar green\nproperty uchar blue\n";
    o << "element face " << mesh.faces.size()
      << "\nproperty list uchar int vertex_indices\nend_header\n";
    auto put = [&](auto v) { o.write(reinterpret_cast<const char*>(&v), sizeof v); };
    for (size_t i = 0; i < mesh.vertices.size(); ++i) {
      const auto& v = mesh.vertices[i];
      if (ascii) {
        o << v.x() << ' ' << v.y() << ' ' << v.z();
        if (normals)
          o << ' ' << mesh.normals[i].x() << ' ' << mesh.normals[i].y() << ' '
            << mesh.normals[i].z();
        if (colours)
          o << ' ' << int(mesh.colors[i][0]) << ' ' << int(mesh.colors[i][1]) << ' '
            << int(mesh.colors[i][2]);
        o << '\n';
        continue;
      }
      for (int k = 0; k < 3; ++k) {
        if (dbl)
          put(v[k]);
        else
          put(static_cast<float>(v[k]));
      }
      if (normals)
        for (int k = 0; k < 3; ++k) put(mesh.normals[i][k]);
      if (colours)
        for (int k = 0; k < 3; ++k) put(mesh.colors[i][k]);
    }
    for (const auto& f : mesh.faces) {
      if (ascii) {
        o << "3 " << f[0] << ' ' << f[1] << ' ' << f[2] << '\n';
        continue;
      }
      put(uint8_t{3});
      for (uint32_t i : f) put(static_cast<int32_t>(i));
    }
  });
}

}  // namespace mvtm
