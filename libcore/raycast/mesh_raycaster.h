// mvtm — ray casting against a triangle mesh: the closest hit along a ray, and an occlusion test
// (drive: the ground under the wheels; gazemap: the surface under a gaze ray, visibility).
//
// Conventions:
//  * A ray is origin + t·direction, t in [t_min, t_max]; the direction need not be unit length
//    and t is measured in units of it (unit direction: t is a distance in model units).
//  * Everything the caller sees is double, in the mesh's world coordinates. Traversal is Embree 3
//    (robust mode: no cracks between triangles that share an edge) on float vertices re-centred on
//    the centre of the mesh's bounds, taken in double, so a road at UTM coordinates (≈ 5·10⁶ m)
//    traverses like one at the origin. The hit is then recomputed in double against the original
//    vertices of the triangle Embree found (Möller–Trumbore), so t, the point and the barycentrics
//    are exact to double rounding, not to float: at a 5·10⁶ offset the point is within ~1e-9 of
//    the true intersection where float would be 0.5 off.
//  * Which triangle is hit is decided in float: two surfaces closer than float resolution of the
//    re-centred mesh (~1e-7 of its extent) along the ray may be confused, and a ray through an
//    edge is given either neighbour. When the double refinement lands a hair outside the chosen
//    triangle (an edge hit), the barycentrics are clamped to it and t is the ray's intersection
//    with its plane. A ray lying in a triangle's plane (no plane intersection) keeps Embree's t.
//  * Barycentrics: point = (1 − u − v)·A + u·B + v·C for the face (A, B, C) as stored; the normal
//    is the unit geometric normal (B − A) × (C − A) (counter-clockwise front), whichever side the
//    ray comes from.
//  * Occluded() answers "is there any surface with t in [t_min, t_max]" in float (no refinement):
//    surfaces within ~1e-7·extent of the interval's ends are ambiguous, so a visibility test
//    between two surface points should stop short of them by a small margin.
//  * Degenerate triangles (zero area) are never hit; a face with a vertex index out of range is an
//    Error at construction.
// Thread safety: construction is not; Closest() and Occluded() are const and may be called from
// several threads at once. The raycaster copies what it needs: the Mesh may be destroyed after.
#pragma once

#include <Eigen/Core>
#include <cstdint>
#include <limits>
#include <memory>
#include <optional>

#include "scene/mesh.h"

namespace mvtm {

struct RayHit {
  double t = 0;                                      // ray parameter of the hit
  uint32_t triangle = 0;                             // index into Mesh::faces
  double u = 0, v = 0;                               // barycentrics of B and C (see above)
  Eigen::Vector3d point = Eigen::Vector3d::Zero();   // origin + t·direction
  Eigen::Vector3d normal = Eigen::Vector3d::Zero();  // unit geometric normal of the triangle
};

class MeshRaycaster {
 public:
  // Builds the acceleration structure (Embree BVH). Throws Error for an index out of range or an
  // Embree failure. An empty mesh is valid (nothing is ever hit).
  explicit MeshRaycaster(const Mesh& mesh);
  ~MeshRaycaster();
  MeshRaycaster(MeshRaycaster&&) noexcept;
  MeshRaycaster& operator=(MeshRaycaster&&) noexcept;
  MeshRaycaster(const MeshRaycaster&) = delete;
  MeshRaycaster& operator=(const MeshRaycaster&) = delete;

  // The closest hit with t in [t_min, t_max], or nullopt. The direction must be non-zero.
  std::optional<RayHit> Closest(const Eigen::Vector3d& origin, const Eigen::Vector3d& direction,
                                double t_min = 0,
                                double t_max = std::numeric_limits<double>::infinity()) const;
  // True when any triangle is hit with t in [t_min, t_max].
  bool Occluded(const Eigen::Vector3d& origin, const Eigen::Vector3d& direction, double t_min,
                double t_max) const;

  // The double origin the float vertices are relative to (centre of the mesh's bounds).
  const Eigen::Vector3d& centre() const;
  size_t triangles() const;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace mvtm
