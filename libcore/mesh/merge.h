// mvtm — closing a dense mesh with a proxy: the proxy's ground laid just beneath the dense surface.
//
// Dense stereo leaves holes where the photos give no match (dark, textureless asphalt, sky edges,
// moving vehicles) and fragments between them; the road must stay closed for rendering. Every
// ground face of the proxy (face normal within 45° of `up`) is appended to the dense mesh moved
// down by `depth_below` along `up`: where the dense road exists it hides the proxy (the depth
// test keeps the nearer surface), where it has holes the proxy shows. No face is dropped by a
// proximity test, so fragments of dense road never punch holes. The proxy's walls are dropped:
// the dense surface replaces them. Lengths in the model's own unit. Normals are recomputed;
// colours dropped (bake them afterwards). Thread safety: pure function.
#pragma once

#include <Eigen/Core>
#include <cstddef>

#include "scene/mesh.h"

namespace mvtm {

struct MergeReport {
  size_t proxy_faces_kept = 0;  // ground faces of the proxy appended
};

Mesh MergeGroundBeneath(const Mesh& dense, const Mesh& proxy, const Eigen::Vector3d& up,
                        double depth_below, MergeReport* report = nullptr);

}  // namespace mvtm
