// mvtm — closing a dense mesh with a proxy (the road corridor): its ground beneath the dense
// surface, its walls behind it.
//
// Dense stereo leaves holes where the photos give no match (dark, textureless asphalt, white
// facades, sky edges, moving vehicles) and fragments between them; the road must stay closed and
// a hole must not show the background. Every face of the proxy is appended to the dense mesh,
// moved away from the camera path so that the dense surface, where it exists, hides it (the
// depth test keeps the nearer surface) and the proxy shows only through the holes:
//   * ground faces (face normal within 45° of `up`) are lowered by `ground_below` along `up`;
//   * wall faces (every other face; a wall's normals face the path) are moved back by
//     `walls_behind` against their vertex normals (or, vertex by vertex, by a given offset: just
//     behind a flat dense facade, DenseFacadeBehindWalls), and a wall's foot (its vertices where
//     the proxy's ground has a vertex) down by the larger of that and `ground_below`, so no gap
//     to nothing opens between the ground's edge and the wall; `walls_behind` < 0 drops the
//     walls (offsets or not).
// No face is dropped by a proximity test, so fragments of dense surface never punch holes.
// Lengths in the model's own unit. Normals are recomputed; colours dropped (bake them
// afterwards). The result's face_kinds say which faces are the proxy's (kFaceFillGround,
// kFaceFillWall; the dense faces keep theirs, else kFaceObserved): dynmask clears what it finds
// mostly where a pixel's ray meets a wall first (a guessed depth). Thread safety: pure function.
#pragma once

#include <Eigen/Core>
#include <cstddef>
#include <limits>
#include <vector>

#include "scene/mesh.h"

namespace mvtm {

struct MergeReport {
  size_t ground_faces = 0, wall_faces = 0;  // proxy faces appended
};

// How far the proxy's ground lies above the dense surface's ground where both are: the median,
// over the dense faces whose normal is within 30° of up (either side) and the proxy ground face
// (normal within 45° of up) nearest to each in the plane across `up` within `reach`, of the proxy
// face's height above the dense face's (centroids, along `up`), counting only heights within
// ±`bound` (canopies and roofs above the road, pits below it, are not the road). Negative: the
// proxy is below. 0 when fewer than 50 pairs are found. A proxy ground fitted too high (a camera
// height from a few sparse points) hides the dense road in front of it; lowering it by this
// much (MergeProxyBehind's ground_below) puts it back under the road.
double ProxyGroundAbove(const Mesh& dense, const Mesh& proxy, const Eigen::Vector3d& up,
                        double reach, double bound);

// Where the dense surface shows a flat facade behind (or in front of) the proxy's walls. For each
// wall vertex of the proxy (a vertex of a face that is not ground; it needs vertex normals, which
// face the path): the dense faces that stand upright (normal within 60° of horizontal) and whose
// horizontal normal is within 45° of the vertex's (either side: a facade seen from the road), at
// most `reach` from the vertex along the wall (horizontally, across its normal), within `rise` of
// its height, and between `front` in front of it and `back` behind it (face centroids). When at
// least `min_faces` are found and the interquartile range of their distances behind the vertex
// is at most `spread` (flat: not a hedge or a tree), the `quantile` of those distances (negative:
// in front); else NaN. Ground vertices get NaN. Lengths in model units. Throws Error on an
// invalid search (reach or rise not > 0, front, back or spread negative, front or back not
// finite, quantile outside [0, 1]) or a proxy without normals.
struct FacadeSearch {
  double reach = 0;                                       // along the wall, > 0
  double rise = std::numeric_limits<double>::infinity();  // above and below the vertex, > 0
  double front = 0;       // farthest in front of the wall a facade face counts, >= 0
  double back = 0;        // farthest behind it, >= 0
  double quantile = 0.9;  // of the faces' distances behind the wall: the wall goes behind most
  size_t min_faces = 10;  // fewer: no facade there
  double spread = std::numeric_limits<double>::infinity();  // interquartile range of their
                                                            // distances above this: no facade
};
std::vector<double> DenseFacadeBehindWalls(const Mesh& dense, const Mesh& proxy,
                                           const Eigen::Vector3d& up, const FacadeSearch& search);

// The proxy needs vertex normals for its walls (Mesh::ComputeNormals) unless walls_behind < 0,
// or walls_behind == 0 with no offsets.
// `wall_offsets` (one per proxy vertex, or empty): where finite, a wall vertex goes back by that
// much instead of `walls_behind` (DenseFacadeBehindWalls plus a gap puts it just behind the dense
// facade, where a hole of the facade then shows nearly the right depth); a foot vertex goes down
// by the larger of its offset and `ground_below`.
Mesh MergeProxyBehind(const Mesh& dense, const Mesh& proxy, const Eigen::Vector3d& up,
                      double ground_below, double walls_behind, MergeReport* report = nullptr,
                      const std::vector<double>& wall_offsets = {});

// Where the walls should stand, from what the photos saw through them.
// The corridor's walls (mesh/corridor.h) stand at the median lateral distance of the sparse
// points; roadmesh --dense moves them back so that the dense surface hides them and they show
// only through its holes. What a hole then shows is a projector's colour at the wall's depth:
// right when the wall lies where the scenery behind the hole is, off by a parallax that grows
// with the error in inverse depth everywhere else (a building a few metres behind the corridor,
// open fields a hundred metres away). The photos' own depth maps say where that scenery is, ray
// by ray.
//
// A sight is a ray from a camera centre to the point its depth map saw. Each sight that meets a
// wall face of the proxy (unmoved) before its point is a sample of the wall there: how far behind
// the wall the point lies, along the wall face's normal (towards the path), clamped to
// [0, search.back]. Cast against the dense surface too (ray parameter 1 at the point), the
// sample is covered when the ray meets the dense surface within 1 ± `tolerance`, a hole when it
// meets none before 1 + `tolerance`, no sample when it meets it before the wall (the wall is
// hidden there), and a covered sample at the dense surface's distance when it meets it between
// the wall and 1 - `tolerance` (the photo saw past it; the wall must not hide it). A wall vertex
// gathers the samples that met the wall within `reach` of it horizontally and `rise` of its
// height. With at least `min_samples` holes, it takes their `quantile`: the median puts the wall
// where it minimises the mean error in inverse depth over the pixels that see that stretch of
// wall through holes (every sample is one pixel: what covers more of the images weighs more).
// With at least `min_samples` covered samples it goes at least as far back as their
// `covered_quantile`, so that it does not hide the dense surface it stands in front of. A vertex
// with neither takes the median of its wall's valued vertices within reach / 2 across up (its
// column above and below it, whatever the wall's lean, and its neighbours'), else of its wall's
// (a wall: wall faces
// connected through shared vertices); NaN when its wall has none (MergeProxyBehind then uses its
// fixed distance), and for every vertex of no wall face. Sights that end before the wall (a tree,
// a parked car in front of it) or never meet one (the ground, the sky) say nothing about it.
// Lengths in model units; UTM-sized coordinates are fine (the ray casters work relative to their
// mesh's centre, the grid relative to the proxy's first vertex). The sights are cast on all cores
// (TBB); memory: about 50 bytes per sight beside the sights themselves.

struct Sight {
  Eigen::Vector3d origin;  // the camera centre
  Eigen::Vector3d point;   // what it saw, != origin
};

struct SeenWallSearch {
  double reach = 0;               // horizontal distance from the vertex, > 0
  double rise = 0;                // above and below its height, > 0
  double back = 0;                // the farthest a wall goes behind its place, > 0 (farther: this)
  double quantile = 0.5;          // of the holes' distances behind, in [0, 1]
  double covered_quantile = 0.9;  // of the covered samples' distances: the least, in [0, 1]
  double tolerance = 0.05;        // dense surface at the point: within this of its ray parameter
  size_t min_samples = 20;        // fewer holes (covered samples): no value from them
};

// One value per proxy vertex (see above). The proxy and the dense surface may be empty (no
// samples: all NaN). Throws Error on an invalid search.
std::vector<double> SeenWallDistances(const Mesh& proxy, const Eigen::Vector3d& up,
                                      const std::vector<Sight>& sights, const Mesh& dense,
                                      const SeenWallSearch& search);

}  // namespace mvtm
