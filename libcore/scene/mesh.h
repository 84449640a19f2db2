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

struct Mesh {
  std::vector<Eigen::Vector3d> vertices;
  std::vector<Eigen::Vector3f> normals;        // empty or one per vertex
  std::vector<std::array<uint8_t, 3>> colors;  // empty or one per vertex
  std::vector<std::array<uint32_t, 3>> faces;
  std::vector<std::string> missing;  // filled by ReadMesh: "normals", "colours", "faces"

  bool has_normals() const { return !normals.empty() && normals.size() == vertices.size(); }
  bool has_colors() const { return !colors.empty() && colors.size() == vertices.size(); }
  // Area-weighted vertex normals from the faces.
  void ComputeNormals();
  // Axis-aligned bounds; (+inf, -inf) for an empty mesh.
  void Bounds(Eigen::Vector3d& lo, Eigen::Vector3d& hi) const;
};

// The faces `faces` of `m` (indices into m.faces, in that order) with the vertices they use, in
// the order they are first used; normals and colours come along when `m` has them.
Mesh SubMesh(const Mesh& m, const std::vector<uint32_t>& faces);

}  // namespace mvtm
