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

#include <string>

#include "scene/mesh.h"

namespace mvtm {

// Throws Error("PATH: ...") when unreadable or when a face index is out of range.
Mesh ReadMesh(const std::string& path);
// Writes PLY (binary unless ascii) atomically, with normals and colours when present.
void WriteMesh(const std::string& path, const Mesh& mesh, bool ascii = false);

}  // namespace mvtm
