// mvtm — triangle meshes (PLY read and written by mvtm itself; OBJ and OFF through OpenMesh).
//
// Conventions:
//  * Vertex positions are double in memory, in world coordinates (metres). A PLY written by
//    mvtm stores positions as double when any coordinate exceeds 1e5 in magnitude (UTM-sized
//    worlds), else as float like COLMAP's meshes; both read back. PLY (ascii, binary little- and
//    big-endian, any numeric property types) is read by mvtm's own reader: OpenMesh would round
//    double positions to float (0.5 m at UTM northings), drop faces with bad indices silently and
//    loop forever on some malformed headers. Every count is checked against the file's size
//    before anything is allocated; indices, list lengths and colours must be integers in range.
//  * Colours are 8-bit RGB, normals unit float vectors; faces are triangles (polygons are
//    triangulated on read, each triangle with its polygon's kind).
//  * Mesh::face_kinds is the face property "uchar mvtm_fill" (scene/mesh.h FaceKind, 0..2),
//    written when the mesh has one per face; readers that do not know it skip it (PLY allows
//    any property), a value outside 0..2 is an error.
//  * ReadMesh() reports what the file lacks (normals, colours, faces) in Mesh::missing rather
//    than failing; a tool that needs an attribute throws with that list.
#pragma once

#include <Eigen/Core>
#include <cstddef>
#include <functional>
#include <string>

#include "scene/mesh.h"

namespace mvtm {

// Throws Error("PATH[:LINE]: ...") when unreadable or malformed (LINE for ASCII bodies).
Mesh ReadMesh(const std::string& path);
// Writes PLY (binary unless ascii) atomically, with normals and colours when present.
void WriteMesh(const std::string& path, const Mesh& mesh, bool ascii = false);

// A PLY written in parts, for a mesh too large to hold: the totals first (the header needs them),
// then the parts in order, each with its own vertex indices (offset by the vertices of the parts
// before it). `parts(faces, emit)` is called twice, with faces false and then true (PLY holds
// every vertex before any face), and must emit the same parts both times; the faces pass may
// leave colours out. The file equals WriteMesh's of the joined mesh byte for byte. Throws Error
// when the parts do not add up to the totals or a face names a vertex outside its part.
struct MeshTotals {
  size_t vertices = 0, faces = 0;
  Eigen::Vector3d lo = Eigen::Vector3d::Zero(), hi = Eigen::Vector3d::Zero();  // vertex bounds
  bool normals = false, colours = false, face_kinds = false;  // face_kinds: "mvtm_fill"
};
using MeshPartEmitter = std::function<void(const Mesh&)>;
void WriteMeshParts(const std::string& path, const MeshTotals& totals,
                    const std::function<void(bool faces, const MeshPartEmitter& emit)>& parts,
                    bool ascii = false);

}  // namespace mvtm
