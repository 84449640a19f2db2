// mvtm — a triangle mesh as data (io/mesh_io.h reads and writes it as PLY and other formats).
//
// Conventions:
//  * Vertex positions are double, in world coordinates of the model's own unit (re-centred
//    before anything reaches float: see render/).
//  * Colours are 8-bit RGB, normals unit float vectors, faces triangles with counter-clockwise
//    winding seen from the front.
// Thread safety: a Mesh is a plain value.
#pragma once

#include <Eigen/Core>
#include <array>
#include <cstdint>
#include <string>
#include <vector>

namespace mvtm {

// What a face is, where a tool knows (Mesh::face_kinds; PLY face property "mvtm_fill").
// roadmesh --dense closes the holes of the surface fused from the photos' depth with its
// corridor: ground under the fused road and walls behind the fused facades. Those are guesses (a
// backdrop at a chosen depth), not surfaces any photo measured.
enum FaceKind : uint8_t {
  kFaceObserved = 0,    // fused from the photos' depth, or of a mesh made otherwise
  kFaceFillGround = 1,  // the corridor's ground, shown through the fused road's holes
  kFaceFillWall = 2,    // a corridor wall, shown through the fused facades' holes
};
constexpr uint8_t kFaceKindCount = 3;

struct Mesh {
  std::vector<Eigen::Vector3d> vertices;
  std::vector<Eigen::Vector3f> normals;        // empty or one per vertex
  std::vector<std::array<uint8_t, 3>> colors;  // empty or one per vertex
  std::vector<std::array<uint32_t, 3>> faces;
  // Empty or one FaceKind per face. A change of the faces that does not keep it one per face
  // leaves it unused (has_face_kinds() false; WriteMesh then leaves the property out).
  std::vector<uint8_t> face_kinds;
  std::vector<std::string> missing;  // filled by ReadMesh: "normals", "colours", "faces"

  bool has_normals() const { return !normals.empty() && normals.size() == vertices.size(); }
  bool has_colors() const { return !colors.empty() && colors.size() == vertices.size(); }
  bool has_face_kinds() const { return !face_kinds.empty() && face_kinds.size() == faces.size(); }
  // Area-weighted vertex normals from the faces.
  void ComputeNormals();
  // Axis-aligned bounds; (+inf, -inf) for an empty mesh.
  void Bounds(Eigen::Vector3d& lo, Eigen::Vector3d& hi) const;
};

// The faces `faces` of `m` (indices into m.faces, in that order) with the vertices they use, in
// the order they are first used; normals, colours and face kinds come along when `m` has them.
Mesh SubMesh(const Mesh& m, const std::vector<uint32_t>& faces);

}  // namespace mvtm
