// roadmesh — a corridor mesh from a COLMAP sparse model, for workspaces without a dense MVS mesh
// (COLMAP without CUDA): a ground strip below the camera path, two side walls at distances fitted
// to the sparse points, open sky; vertex colours are the weighted mean of the images (the
// Lambertian baseline). Writes WS/mesh.ply. The algorithm and its limits: man roadmesh(1).
//
// Conventions: the model's units (metres for a metric model); double precision throughout
// (UTM-sized coordinates); the path is the image centres ordered along the road, so the
// workspace must be one road fragment that does not turn back on itself.
#pragma once

#include <cstddef>
#include <string>

namespace mvtm {

struct RoadMeshOptions {
  std::string workspace;
  double width = 8.0;         // road width (m): ground points within width/2; walls ≥ width/2 + 1
  double wall_height = 10.0;  // wall height above the ground (m), (0, 200]
  double resolution = 0.5;    // grid spacing along and across (m), [0.05, 5]
  bool no_colours = false;    // write no vertex colours (and open no GL context)
  bool dense =
      false;  // fuse densify's stereo/ depth maps; the corridor ground only where they leave holes
  double voxel = 0.1;     // --dense: voxel size as a fraction of the median camera spacing, (0, 10]
  double max_depth = 40;  // --dense: depth used, in median camera spacings, (0, 1000]
  int min_agree = 2;      // --dense: other views that must confirm a depth pixel, 1..16
  double ground_below = 0;  // --dense: corridor ground lowered by this many voxels (0: at its
                            // fitted height), [0, 100]
  bool force = false;       // replace an existing mesh
  std::string gl = "auto";  // auto | egl | osmesa (depth maps for the colour visibility test)
  bool quiet = false;

  // Throws UsageError naming the bad value and the allowed range.
  void Check() const;
};

struct RoadMeshReport {
  size_t images = 0, points = 0;  // registered images, sparse points
  size_t vertices = 0, faces = 0;
  size_t stations = 0;                   // cross-sections along the path
  double path_length = 0;                // smoothed camera path (m), without the end extensions
  double camera_height = 0;              // camera height above the ground used
  size_t ground_points = 0;              // sparse points that fixed it (0: the default)
  double left_wall = 0, right_wall = 0;  // median wall distances (m)
  size_t refined_vertices = 0;           // ground vertices moved by the height field
  size_t coloured = 0;                   // vertices seen by at least one image
  size_t dense_views = 0,
         dense_faces = 0;     // --dense: depth maps fused, triangles of the fused surface
  size_t corridor_faces = 0;  // --dense: corridor ground triangles kept in the holes
  std::string gl;
  std::string mesh_path;
};

RoadMeshReport RunRoadMesh(const RoadMeshOptions& options);

}  // namespace mvtm
