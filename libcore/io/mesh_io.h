// mvtm — triangle meshes (PLY, through OpenMesh).
//
// Conventions:
//  * Vertex positions are double in memory, in world coordinates (metres). A PLY written by
//    mvtm stores positions as double when any coordinate exceeds 1e5 in magnitude (UTM-sized
//    worlds), else as float like COLMAP's meshes; both read back. OpenMesh reads every mesh
//    format except double-precision PLY, which it would round to float (0.5 m at UTM northings):
//    those are read directly.
//  * Colours are 8-bit RGB, normals unit float vectors; faces are triangles (polygons are
//    triangulated on read).
//  * ReadMesh() reports what the file lacks (normals, colours, faces) in Mesh::missing rather
//    than failing; a tool that needs an attribute throws with that list.
#pragma once

#include <array>
#include <cstdint>
#include <string>
#include <vector>

#include <Eigen/Core>

namespace mvtm {

struct Mesh {
  std::vector<Eigen::Vector3d> vertices;
  std::vector<Eigen::Vector3f> normals;             // empty or one per vertex
  std::vector<std::array<uint8_t, 3>> colors;       // empty or one per vertex
  std::vector<std::array<uint32_t, 3>> faces;
  std::vector<std::string> missing;                 // filled by ReadMesh: "normals", "colours", "faces"

  bool has_normals() const { return !normals.empty() && normals.size() == vertices.size(); }
  bool has_colors() const { return !colors.empty() && colors.size() == vertices.size(); }
  // Area-weighted vertex normals from the faces.
  void ComputeNormals();
  // Axis-aligned bounds; (+inf, -inf) for an empty mesh.
  void Bounds(Eigen::Vector3d& lo, Eigen::Vector3d& hi) const;
};

// Throws Error("PATH: ...") when unreadable or when a face index is out of range.
Mesh ReadMesh(const std::string& path);
// Writes PLY (binary unless ascii) atomically, with normals and colours when present.
void WriteMesh(const std::string& path, const Mesh& mesh, bool ascii = false);

}  // namespace mvtm
