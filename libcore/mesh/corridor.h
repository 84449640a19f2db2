// mvtm — a road corridor mesh from a sparse model (roadmesh; thesis §4.1 generalised along the
// trajectory): a ground strip below the camera path, two side walls at distances fitted to the
// sparse points, open sky.
//
// The path is the image centres ordered along the road (distance from one end of the set, so the
// images must be one road fragment that turns by less than about 180°), pointing the way the
// cameras look, smoothed by a local linear fit, extended 30 past both ends and cut into
// cross-sections ("stations") every `resolution` of arc length. Each station has a right-handed
// frame forward × left = up, where up is the cameras' −y axis (smoothed along the path).
//   * Camera height: median depth below the path of the points within width/4 (else width/2) of
//     it and 0.5–4 below it; 1.65 (KITTI) when fewer than 10 such points exist.
//   * Walls: per station, the median lateral distance of the points beside the road (within
//     ±5 along the path) between the ground + 0.5 and the wall top + 5, clamped to
//     [width/2 + 1, 30]; gaps interpolated (8 where a side has no points), then smoothed.
//   * Ground: a height field from the right wall to the left, the median height of the points
//     within 1 of the ground plane around each vertex, smoothed; unmeasured vertices stay on the
//     plane.
//
// Scale: every length above — the options and the constants — is in metre-equivalents and is
// multiplied by `CorridorOptions::unit` (model units per metre-equivalent: 1 for a metric model),
// so a model scaled by s and built with unit × s gives the corridor scaled by s (the same grid:
// counts come from ratios of lengths, rounded with a 1e-9 tolerance). The results (Corridor) are
// in model units.
// Conventions: poses are COLMAP's (world-to-camera, camera y down); double precision throughout,
// so UTM-sized coordinates are fine.
// The mesh: ground grid vertices first (rows = stations, columns right to left), then the left
// wall, then the right wall (own vertices: a sharp crease); triangles wound counter-clockwise seen
// from the road (ground normals up, walls facing the path); area-weighted vertex normals; no
// colours (mesh/vertex_colours.h bakes them).
// Thread safety: pure functions of their arguments.
#pragma once

#include <cstddef>

#include "scene/mesh.h"
#include "scene/reconstruction.h"

namespace mvtm {

// Lengths in metre-equivalents: each is multiplied by `unit` to get model units.
struct CorridorOptions {
  double width = 8.0;         // road width: ground points within width/4 (else width/2) of the
                              // path; walls at least width/2 + 1 from it
  double wall_height = 10.0;  // wall height above the ground
  double resolution = 0.5;    // grid spacing along and across
  double unit = 1;            // model units per metre-equivalent (1: a metric model), > 0
};

// The corridor and what it was fitted to; lengths in model units.
struct Corridor {
  Mesh mesh;                             // vertices, faces, normals (see above)
  size_t stations = 0;                   // cross-sections along the path
  double path_length = 0;                // smoothed camera path, without the end extensions
  double camera_height = 0;              // camera height above the ground used
  size_t ground_points = 0;              // sparse points that fixed it (0: the default)
  double left_wall = 0, right_wall = 0;  // median wall distances
  size_t refined_vertices = 0;           // ground vertices moved by the height field
};

// Builds the corridor along the registered images of `rec` (in ImagesByName() order) fitted to
// its 3-D points. Throws Error with fewer than two images, when the cameras do not move, or when
// the path runs along the cameras' up axis. Options are not range-checked (the tool does).
Corridor BuildCorridor(const Reconstruction& rec, const CorridorOptions& options);

}  // namespace mvtm
