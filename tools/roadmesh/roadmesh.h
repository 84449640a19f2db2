// roadmesh — a corridor mesh from a COLMAP sparse model, for workspaces without a dense MVS mesh
// (COLMAP without CUDA): a ground strip below the camera path, two side walls at distances fitted
// to the sparse points, open sky; vertex colours are the weighted mean of the images (the
// Lambertian baseline). Writes WS/mesh.ply. The algorithm and its limits: man roadmesh(1).
//
// Scale: the corridor's lengths (options and constants) are metre-equivalents times the model's
// unit (model units per metre-equivalent): 1 with --metric, else the camera height the scene
// shows divided by 1.65 m (EstimateSceneUnit), so the mesh does not depend on the model's scale.
// Reported lengths are in model units.
// Conventions: double precision throughout (UTM-sized coordinates); the path is the image centres
// ordered along the road, so the workspace must be one road fragment that does not turn back on
// itself.
#pragma once

#include <cstddef>
#include <string>

#include "render/context.h"
#include "run/option_table.h"
#include "scene/reconstruction.h"

namespace mvtm {

struct RoadMeshOptions {
  std::string workspace;
  // Lengths in metre-equivalents (metres with `metric`, else scaled by the scene's unit).
  double width = 8.0;         // road width: ground points within width/4 (else width/2); walls
                              // ≥ width/2 + 1; (0, 50]
  double wall_height = 10.0;  // wall height above the ground, (0, 200]
  double resolution = 0.5;    // grid spacing along and across, [0.05, 5]
  bool metric = false;        // the model is in metres (unit 1); else the unit is estimated
  bool no_colours = false;    // write no vertex colours (and open no GL context)
  bool dense =
      false;  // fuse densify's stereo/ depth maps; the corridor ground only where they leave holes
  double voxel = 0.1;     // --dense: voxel size as a fraction of the median camera spacing, (0, 10]
  double max_depth = 40;  // --dense: depth used, in median camera spacings, (0, 1000]
  int min_agree = 2;      // --dense: other views that must confirm a depth pixel, 1..16
  double ground_below = 0;     // --dense: corridor ground lowered by this many voxels (0: at its
                               // fitted height), [0, 100]
  double walls_behind = 20;    // --dense: corridor walls moved back by this many voxels behind the
                               // fused surface where no photo saw through them; -1: no walls,
                               // [0, 1000]
  double walls_gap = -1;       // --dense: where the fused surface shows a flat facade near a wall,
                               // the wall goes this many voxels behind it instead; < 0: never
  bool no_seen_walls = false;  // --dense: walls at walls_behind, not where the photos saw
  double walls_reach = 2;      // --dense: seen depth gathered within this many m-eq. along a
                               // wall vertex and half as many up or down, [0.05, 100]
  double agree_tolerance = 0.01;    // --dense: confirmation within this fraction of the depth
  bool strict_agree = false;        // --dense: min_agree confirming views even where fewer see it
  bool force = false;               // replace an existing mesh, even one roadmesh did not make
  GlBackend gl = GlBackend::kAuto;  // depth maps for the colour visibility test
  bool quiet = false;

  // Throws UsageError naming the bad value and the allowed range.
  void Check() const;
};

// The option table (run/option_table.h) bound to `o`: --help, checks, provenance and the
// staleness key of the mesh all come from it.
OptionTable DeclareOptions(RoadMeshOptions& o);

// The model's length unit, from the scene (no metric assumption).
//   Camera height: every sparse point an image observes below its principal point and in the
//   bottom 40 % of its rows (the road ahead) is measured from the camera nearest to it (the car
//   drove over it, so the camera's pitch and the road's slope hardly matter): height h along that
//   camera's y axis (down), lateral offset x, offset z along its view. Road points of the lane
//   are kept: h > 0, |x| <= h and |z| <= h (ratios, so scale-free). An image with at least 5
//   such points gives their median; the camera height is the median over those images (at least
//   3), and unit = height / 1.65 (KITTI's dashcam height, metres).
//   Fallback, with fewer images: unit = median spacing of consecutive cameras (name order) / 1 m
//   (a typical frame spacing); 1 when the cameras do not move.
struct SceneUnit {
  double unit = 1;                  // model units per metre-equivalent
  const char* source = "--metric";  // "camera height" | "camera spacing" | "--metric" | "none"
  double camera_height = 0;         // measured camera height (model units), 0 unless from it
  size_t points = 0;                // road points measured (with repeats across images)
  size_t images = 0;                // images that gave a height
  double spacing = 0;               // median camera spacing (model units), the fallback's input
};

// Throws nothing for a model without points (the fallback); images need their cameras.
SceneUnit EstimateSceneUnit(const Reconstruction& rec);
// Where the unit came from, for the summary: "--metric", "camera height 0.3459 from 2222 points
// in 45 images / 1.65 m", "median camera spacing 0.25 / 1 m: too few road points below the
// cameras", "the cameras do not move".
std::string DescribeSceneUnit(const SceneUnit& unit);

struct RoadMeshReport {
  size_t images = 0, points = 0;  // registered images, sparse points
  SceneUnit unit;                 // the unit used (metric: 1)
  size_t vertices = 0, faces = 0;
  size_t stations = 0;  // cross-sections along the path
  // Lengths in model units.
  double path_length = 0;                // smoothed camera path, without the end extensions
  double camera_height = 0;              // camera height above the ground used
  size_t ground_points = 0;              // sparse points that fixed it (0: the default)
  double left_wall = 0, right_wall = 0;  // median wall distances
  size_t refined_vertices = 0;           // ground vertices moved by the height field
  size_t coloured = 0;                   // vertices seen by at least one image
  size_t dense_views = 0,
         dense_faces = 0;          // --dense: depth maps fused, triangles of the fused surface
  size_t corridor_faces = 0;       // --dense: corridor ground triangles kept in the holes
  size_t corridor_wall_faces = 0;  // --dense: corridor wall triangles behind the fused surface
  double ground_lowered = 0;       // --dense: how far the corridor ground went down, model units:
                                   // --ground-below, plus as much as it lay above the fused road
  size_t walls_seen = 0;           // --dense: wall vertices put where the photos saw through them
  size_t walls_at_facades = 0;     // --dense: wall vertices put just behind a fused facade
  std::string gl;
  std::string mesh_path;
  bool up_to_date = false;  // mesh.ply was up to date: nothing was built (the rest is unset)
  std::string why;          // why an existing mesh was rebuilt ("1 redone: --width changed")
};

RoadMeshReport RunRoadMesh(const RoadMeshOptions& options);

}  // namespace mvtm
