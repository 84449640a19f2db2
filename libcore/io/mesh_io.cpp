// PLY through OpenMesh (http://paulbourke.net/dataformats/ply/).
// GCC 12 reports a false maybe-uninitialized inside OpenMesh's property templates (clang has
// no such warning and would warn of the unknown option).
#if defined(__GNUC__) && !defined(__clang__)
#pragma GCC diagnostic ignored "-Wmaybe-uninitialized"
#endif
#include "io/mesh_io.h"

#include <Eigen/Geometry>
#include <OpenMesh/Core/IO/MeshIO.hh>
#include <OpenMesh/Core/Mesh/TriMesh_ArrayKernelT.hh>
#include <algorithm>
#include <charconv>
#include <cmath>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <limits>
#include <sstream>

#include "base/atomic_file.h"
#include "base/error.h"
#include "base/text.h"

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

enum class PlyType { kInt8, kUint8, kInt16, kUint16, kInt32, kUint32, kFloat32, kFloat64 };

bool PlyTypeFromName(const std::string& t, PlyType& out) {
  static const std::pair<const char*, PlyType> kNames[] = {
      {"char", PlyType::kInt8},      {"int8", PlyType::kInt8},       {"uchar", PlyType::kUint8},
      {"uint8", PlyType::kUint8},    {"short", PlyType::kInt16},     {"int16", PlyType::kInt16},
      {"ushort", PlyType::kUint16},  {"uint16", PlyType::kUint16},   {"int", PlyType::kInt32},
      {"int32", PlyType::kInt32},    {"uint", PlyType::kUint32},     {"uint32", PlyType::kUint32},
      {"float", PlyType::kFloat32},  {"float32", PlyType::kFloat32}, {"double", PlyType::kFloat64},
      {"float64", PlyType::kFloat64}};
  for (const auto& [name, type] : kNames)
    if (t == name) {
      out = type;
      return true;
    }
  return false;
}

size_t PlySize(PlyType t) {
  switch (t) {
    case PlyType::kInt8:
    case PlyType::kUint8:
      return 1;
    case PlyType::kInt16:
    case PlyType::kUint16:
      return 2;
    case PlyType::kInt32:
    case PlyType::kUint32:
    case PlyType::kFloat32:
      return 4;
    case PlyType::kFloat64:
      return 8;
  }
  return 8;
}

struct PlyProperty {
  std::string name;
  PlyType type = PlyType::kFloat32;
  bool is_list = false;
  PlyType count_type = PlyType::kUint8;  // lists only
};
struct PlyElement {
  std::string name;
  size_t count = 0;
  long line = 0;  // header line declaring it
  std::vector<PlyProperty> props;
  // Fewest bytes one element can take in the body (binary), or fewest values (ascii).
  size_t MinBytes() const {
    size_t n = 0;
    for (const auto& p : props) n += p.is_list ? PlySize(p.count_type) : PlySize(p.type);
    return n;
  }
};
struct PlyHeader {
  std::string format;
  std::vector<PlyElement> elements;
  size_t bytes = 0;  // header length
  long lines = 0;
};

// Largest element count accepted (4·10⁹ would not fit the 32-bit indices of faces anyway).
constexpr uint64_t kMaxPlyCount = 0xffffffffull;

size_t ParsePlyCount(const std::string& tok, const std::string& path, long line) {
  if (tok.empty() || tok.find_first_not_of("0123456789") != std::string::npos)
    throw Error(path, line, "element count '" + tok + "' is not a non-negative integer");
  if (tok.size() > 10 || std::stoull(tok) > kMaxPlyCount)
    throw Error(path, line, "element count " + tok + " is beyond 2^32-1");
  return static_cast<size_t>(std::stoull(tok));
}

PlyProperty ParsePlyProperty(std::istringstream& ls, const std::string& path, long line) {
  PlyProperty p;
  std::string type, count_type;
  ls >> type;
  if (type == "list") {
    p.is_list = true;
    ls >> count_type >> type;
    if (!PlyTypeFromName(count_type, p.count_type))
      throw Error(path, line, "unknown PLY list count type '" + count_type + "'");
  }
  if (!PlyTypeFromName(type, p.type)) throw Error(path, line, "unknown PLY type '" + type + "'");
  if (!(ls >> p.name)) throw Error(path, line, "property has no name");
  return p;
}

// Reads and checks the header. OpenMesh 9's PLY reader loops forever on a header cut before
// "end_header", so every PLY passes through here first.
PlyHeader ReadPlyHeader(std::istream& in, const std::string& path) {
  PlyHeader h;
  std::string line;
  long n = 0;
  while (std::getline(in, line)) {
    ++n;
    h.bytes += line.size() + 1;
    if (!line.empty() && line.back() == '\r') line.pop_back();
    std::istringstream ls(line);
    std::string key;
    ls >> key;
    if (n == 1 && key != "ply") throw Error(path, 1, "not a PLY file (first line is not 'ply')");
    if (key == "format") {
      // OpenMesh 9 loops forever on a format line it does not know: checked here.
      std::string version;
      if (!h.format.empty()) throw Error(path, n, "second 'format' line");
      ls >> h.format >> version;
      if (h.format != "ascii" && h.format != "binary_little_endian" &&
          h.format != "binary_big_endian")
        throw Error(path, n, "unknown PLY format '" + h.format + "'");
      if (version != "1.0") throw Error(path, n, "unsupported PLY version '" + version + "'");
    } else if (key == "element") {
      PlyElement e;
      std::string count;
      if (!(ls >> e.name >> count)) throw Error(path, n, "bad element line");
      e.count = ParsePlyCount(count, path, n);
      e.line = n;
      h.elements.push_back(e);
    } else if (key == "property") {
      if (h.elements.empty()) throw Error(path, n, "property before any element");
      h.elements.back().props.push_back(ParsePlyProperty(ls, path, n));
    } else if (key == "end_header") {
      if (h.format.empty()) throw Error(path, n, "PLY header has no 'format' line");
      h.lines = n;
      return h;
    }
    if (h.bytes > 65536) break;
  }
  throw Error(path, n, "PLY header has no 'end_header' (truncated file?)");
}

// Refuses counts the file cannot hold before anything is allocated (a header claiming 2^32
// faces in a 1 kB file): binary elements need MinBytes() each, ascii ones two bytes a value.
void CheckPlyCounts(const PlyHeader& h, uint64_t file_size, const std::string& path) {
  bool ascii = h.format == "ascii";
  uint64_t body = file_size > h.bytes ? file_size - h.bytes : 0, need = 0;
  for (const auto& e : h.elements) {
    uint64_t each = ascii ? 2 * e.props.size() : e.MinBytes();
    if (e.props.empty() && e.count > 0)
      throw Error(path, e.line, "element " + e.name + " declares no properties");
    need += each * e.count;
    if (each > 0 && (e.count > body / each || need > body))
      throw Error(path, e.line,
                  "element " + e.name + " claims " + std::to_string(e.count) +
                      " entries, more than the file's " + std::to_string(body) +
                      " bytes of data can hold (truncated or corrupt file?)");
  }
}

// Reads PLY bodies (ascii or binary_little_endian, any numeric types): vertex x y z [nx ny nz]
// [red green blue], faces as index lists (polygons fanned into triangles). Every value is
// checked: indices in range, colours 0..255, positions finite.
class PlyBodyReader {
 public:
  PlyBodyReader(std::istream& in, const PlyHeader& h, const std::string& path)
      : in_(in),
        ascii_(h.format == "ascii"),
        swap_(h.format == "binary_big_endian"),
        path_(path),
        line_(h.lines + 1) {}

  double Value(PlyType t) {
    if (ascii_) return AsciiValue();
    unsigned char b[8];
    const size_t n = PlySize(t);
    if (!in_.read(reinterpret_cast<char*>(b), static_cast<std::streamsize>(n)))
      Fail("truncated PLY body");
    if (swap_) std::reverse(b, b + n);
    auto get = [&](auto v) {
      std::memcpy(&v, b, sizeof v);
      return static_cast<double>(v);
    };
    switch (t) {
      case PlyType::kInt8:
        return get(int8_t{});
      case PlyType::kUint8:
        return get(uint8_t{});
      case PlyType::kInt16:
        return get(int16_t{});
      case PlyType::kUint16:
        return get(uint16_t{});
      case PlyType::kInt32:
        return get(int32_t{});
      case PlyType::kUint32:
        return get(uint32_t{});
      case PlyType::kFloat32:
        return get(float{});
      case PlyType::kFloat64:
        return get(double{});
    }
    return 0;
  }
  // An integer value in [0, limit): list counts, face indices, colours.
  uint32_t Index(PlyType t, double limit, const char* what) {
    double d = Value(t);
    if (!(d >= 0 && d < limit) || d != std::floor(d))
      Fail(std::string(what) + " " + FormatDouble(d) + " is out of range (0 to " +
           FormatDouble(limit - 1) + ")");
    return static_cast<uint32_t>(d);
  }
  [[noreturn]] void Fail(const std::string& what) const {
    throw Error(path_, ascii_ ? line_ : 0, what);
  }

 private:
  double AsciiValue() {
    int c;
    while ((c = in_.peek()) == ' ' || c == '\t' || c == '\r' || c == '\n') {
      if (c == '\n') ++line_;
      in_.get();
    }
    std::string tok;
    while ((c = in_.peek()) != EOF && !std::isspace(c)) tok.push_back(static_cast<char>(in_.get()));
    if (tok.empty()) Fail("truncated PLY body");
    double v = 0;
    const char* end = tok.data() + tok.size();
    auto r = std::from_chars(tok.data(), end, v);
    if (r.ec != std::errc() || r.ptr != end) Fail("'" + tok + "' is not a number");
    return v;
  }

  std::istream& in_;
  bool ascii_, swap_;
  std::string path_;
  long line_;
};

void ReadPlyVertices(PlyBodyReader& r, const PlyElement& e, Mesh& m, const std::string& path) {
  bool has_n = false, has_c = false;
  int xyz = 0;
  for (const auto& p : e.props) {
    has_n |= p.name == "nx";
    has_c |= p.name == "red";
    xyz += !p.is_list && (p.name == "x" || p.name == "y" || p.name == "z");
  }
  if (xyz != 3) throw Error(path, e.line, "element vertex needs the properties x, y and z");
  m.vertices.reserve(e.count);
  for (size_t i = 0; i < e.count; ++i) {
    Eigen::Vector3d v(0, 0, 0);
    Eigen::Vector3f nrm(0, 0, 0);
    std::array<uint8_t, 3> col{0, 0, 0};
    for (const auto& p : e.props) {
      if (p.is_list) {
        uint32_t cnt = r.Index(p.count_type, 1 << 16, "list length");
        for (uint32_t k = 0; k < cnt; ++k) r.Value(p.type);
        continue;
      }
      static const char* kNames[] = {"x", "y", "z", "nx", "ny", "nz", "red", "green", "blue"};
      int which = 0;
      while (which < 9 && p.name != kNames[which]) ++which;
      if (which >= 6 && which < 9) {
        col[static_cast<size_t>(which - 6)] =
            static_cast<uint8_t>(r.Index(p.type, 256, p.name.c_str()));
        continue;
      }
      double d = r.Value(p.type);
      if (which < 3) v[which] = d;
      if (which >= 3 && which < 6) nrm[which - 3] = static_cast<float>(d);
    }
    if (!v.allFinite()) r.Fail("vertex " + std::to_string(i) + " is not finite");
    m.vertices.push_back(v);
    if (has_n) m.normals.push_back(nrm);
    if (has_c) m.colors.push_back(col);
  }
  if (!has_n) m.missing.push_back("normals");
  if (!has_c) m.missing.push_back("colours");
}

void ReadPlyFaces(PlyBodyReader& r, const PlyElement& e, Mesh& m) {
  double nv = static_cast<double>(m.vertices.size());
  m.faces.reserve(e.count);
  bool kinds = false;
  for (const auto& p : e.props) kinds |= !p.is_list && p.name == "mvtm_fill";
  if (kinds) m.face_kinds.reserve(e.count);
  std::vector<uint32_t> idx;
  for (size_t i = 0; i < e.count; ++i) {
    const size_t before = m.faces.size();
    uint8_t kind = kFaceObserved;
    for (const auto& p : e.props) {
      bool indices = p.is_list && (p.name == "vertex_indices" || p.name == "vertex_index");
      if (!p.is_list) {
        if (p.name == "mvtm_fill")
          kind = static_cast<uint8_t>(r.Index(p.type, kFaceKindCount, "mvtm_fill"));
        else
          r.Value(p.type);
        continue;
      }
      uint32_t cnt = r.Index(p.count_type, 1 << 16, "list length");
      idx.resize(cnt);
      for (auto& x : idx) x = indices ? r.Index(p.type, nv, "face index") : (r.Value(p.type), 0u);
      if (indices)
        for (size_t k = 2; k < cnt; ++k) m.faces.push_back({idx[0], idx[k - 1], idx[k]});
    }
    if (kinds) m.face_kinds.insert(m.face_kinds.end(), m.faces.size() - before, kind);
  }
}

Mesh ReadPlyBody(std::istream& in, const PlyHeader& h, const std::string& path) {
  PlyBodyReader r(in, h, path);
  Mesh m;
  bool seen_vertices = false;
  for (const auto& e : h.elements) {
    if (e.name == "vertex") {
      ReadPlyVertices(r, e, m, path);
      seen_vertices = true;
    } else if (e.name == "face") {
      if (!seen_vertices) throw Error(path, e.line, "element face comes before element vertex");
      ReadPlyFaces(r, e, m);
    } else {
      for (size_t i = 0; i < e.count; ++i)
        for (const auto& p : e.props) {
          uint32_t cnt = p.is_list ? r.Index(p.count_type, 1 << 16, "list length") : 1;
          for (uint32_t k = 0; k < cnt; ++k) r.Value(p.type);
        }
    }
  }
  if (!seen_vertices) throw Error(path, 0, "PLY has no element vertex");
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
    std::error_code ec;
    uint64_t size = std::filesystem::file_size(path, ec);
    CheckPlyCounts(h, ec ? 0 : size, path);
    // mvtm's own reader for every PLY: it keeps double positions (OpenMesh rounds them to
    // float), refuses bad indices (OpenMesh drops such faces) and never loops on bad headers.
    return ReadPlyBody(in, h, path);
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
  MeshTotals t;
  t.vertices = mesh.vertices.size();
  t.faces = mesh.faces.size();
  mesh.Bounds(t.lo, t.hi);
  t.normals = mesh.has_normals();
  t.colours = mesh.has_colors();
  t.face_kinds = mesh.has_face_kinds();
  WriteMeshParts(
      path, t, [&](bool, const MeshPartEmitter& emit) { emit(mesh); }, ascii);
}

void WriteMeshParts(const std::string& path, const MeshTotals& t,
                    const std::function<void(bool faces, const MeshPartEmitter& emit)>& parts,
                    bool ascii) {
  const bool dbl =
      t.vertices > 0 && std::max(t.lo.cwiseAbs().maxCoeff(), t.hi.cwiseAbs().maxCoeff()) > 1e5;
  WriteBinaryAtomic(path, [&](std::ostream& o) {
    o << "ply\nformat " << (ascii ? "ascii" : "binary_little_endian") << " 1.0\n"
      << "comment mvtm\nelement vertex " << t.vertices << "\n";
    const char* pt = dbl ? "double" : "float";
    o << "property " << pt << " x\nproperty " << pt << " y\nproperty " << pt << " z\n";
    if (t.normals) o << "property float nx\nproperty float ny\nproperty float nz\n";
    if (t.colours) o << "property uchar red\nproperty uchar green\nproperty uchar blue\n";
    o << "element face " << t.faces << "\nproperty list uchar int vertex_indices\n";
    if (t.face_kinds) o << "property uchar mvtm_fill\n";
    o << "end_header\n";
    auto put = [&](auto v) { o.write(reinterpret_cast<const char*>(&v), sizeof v); };
    size_t vertices = 0;
    parts(false, [&](const Mesh& mesh) {
      if (!mesh.vertices.empty() &&
          ((t.normals && !mesh.has_normals()) || (t.colours && !mesh.has_colors())))
        throw Error(path, 0, "a part lacks the normals or colours the totals announce");
      for (size_t i = 0; i < mesh.vertices.size(); ++i) {
        const auto& v = mesh.vertices[i];
        if (ascii) {
          o << v.x() << ' ' << v.y() << ' ' << v.z();
          if (t.normals)
            o << ' ' << mesh.normals[i].x() << ' ' << mesh.normals[i].y() << ' '
              << mesh.normals[i].z();
          if (t.colours)
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
        if (t.normals)
          for (int k = 0; k < 3; ++k) put(mesh.normals[i][k]);
        if (t.colours)
          for (int k = 0; k < 3; ++k) put(mesh.colors[i][k]);
      }
      vertices += mesh.vertices.size();
    });
    size_t faces = 0, base = 0;
    parts(true, [&](const Mesh& mesh) {
      if (t.face_kinds && !mesh.faces.empty() && !mesh.has_face_kinds())
        throw Error(path, 0, "a part lacks the face kinds the totals announce");
      for (size_t j = 0; j < mesh.faces.size(); ++j) {
        const auto& f = mesh.faces[j];
        for (uint32_t i : f)
          if (i >= mesh.vertices.size())
            throw Error(path, 0, "face index " + std::to_string(base + i) + " out of range");
        if (ascii) {
          o << "3 " << base + f[0] << ' ' << base + f[1] << ' ' << base + f[2];
          if (t.face_kinds) o << ' ' << int(mesh.face_kinds[j]);
          o << '\n';
          continue;
        }
        put(uint8_t{3});
        for (uint32_t i : f) put(static_cast<int32_t>(base + i));
        if (t.face_kinds) put(mesh.face_kinds[j]);
      }
      base += mesh.vertices.size();
      faces += mesh.faces.size();
    });
    if (vertices != t.vertices || base != t.vertices || faces != t.faces)
      throw Error(path, 0,
                  "the parts hold " + std::to_string(vertices) + " vertices and " +
                      std::to_string(faces) + " faces, the header " + std::to_string(t.vertices) +
                      " and " + std::to_string(t.faces));
  });
}

}  // namespace mvtm
