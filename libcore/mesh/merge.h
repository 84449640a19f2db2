// mvtm — closing a dense mesh with a proxy: the proxy's ground where the dense surface is missing.
//
// Dense stereo leaves holes where the photos give no match (textureless asphalt, sky edges,
// moving vehicles); the road must stay closed for rendering. The corridor's ground faces (face
// normal within 45° of `up`) whose centroid has no dense vertex within `radius` are appended to
// the dense mesh; everything else of the proxy (its walls) is dropped, since the dense surface
// replaces them. Lengths in the model's own unit. Normals are recomputed; colours dropped (bake
// them afterwards). Thread safety: pure function.
#pragma once

#include <cstddef>

#include <Eigen/Core>

#include "scene/mesh.h"

namespace mvtm {

struct MergeReport {
  size_t proxy_faces_kept = 0;  // ground faces of the proxy appended
};

Mesh MergeGroundWhereMissing(const Mesh& dense, const Mesh& proxy, const Eigen::Vector3d& up, double radius,
                             MergeReport* report = nullptr);

}  // namespace mvtm
