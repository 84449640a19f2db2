// Reconstruction helpers against hand-derived values: ObservedDepthQuantile on a model whose
// points sit at known depths in front of known cameras, and the same model moved by a similarity.
#include "scene/reconstruction.h"

#include <gtest/gtest.h>

#include <Eigen/Geometry>

namespace mvtm {
namespace {

// Two cameras looking down +z from x = 0 and x = 2 (identity rotation, world-to-camera t = -C),
// and ten points at z = 1..10 on the axis of the first, each seen by both: the 20 depths are
// 1..10 twice (a camera's depth of a point is its z, whatever the sideways offset).
Reconstruction Line(double scale, const Eigen::Vector3d& offset) {
  Reconstruction rec;
  for (uint32_t id : {1u, 2u}) {
    ImageRecord im;
    im.id = id;
    const Eigen::Vector3d c = scale * Eigen::Vector3d(2.0 * (id - 1), 0, 0) + offset;
    im.world_to_camera = Rigid3d(Eigen::Quaterniond::Identity(), -c);
    rec.images[id] = im;
  }
  for (uint64_t k = 1; k <= 10; ++k) {
    Point3D p;
    p.id = k;
    p.xyz = scale * Eigen::Vector3d(0, 0, double(k)) + offset;
    p.track = {{1, 0}, {2, 0}};
    rec.points3D[k] = p;
  }
  return rec;
}

TEST(Reconstruction, ObservedDepthQuantileIsTheQuantileOfEveryObservation) {
  const Reconstruction rec = Line(1, Eigen::Vector3d::Zero());
  // Sorted depths 1,1,2,2,...,10,10: index floor(q·20) (clamped to 19).
  EXPECT_EQ(ObservedDepthQuantile(rec, 0.0), 1.0);
  EXPECT_EQ(ObservedDepthQuantile(rec, 0.5), 6.0);
  EXPECT_EQ(ObservedDepthQuantile(rec, 0.98), 10.0);
  EXPECT_EQ(ObservedDepthQuantile(rec, 0.89), 9.0);
  // Scaled by 0.2 at UTM coordinates: the same quantile, scaled.
  const Reconstruction moved = Line(0.2, Eigen::Vector3d(451000, 5410000, 120));
  EXPECT_NEAR(ObservedDepthQuantile(moved, 0.5), 1.2, 1e-9);
  EXPECT_NEAR(ObservedDepthQuantile(moved, 0.98), 2.0, 1e-9);
}

TEST(Reconstruction, ObservedDepthQuantileLeavesOutWhatNoCameraSeesInFront) {
  Reconstruction rec = Line(1, Eigen::Vector3d::Zero());
  for (auto& [k, p] : rec.points3D) p.xyz.z() = -p.xyz.z();  // every point behind both cameras
  EXPECT_EQ(ObservedDepthQuantile(rec, 0.98), 0.0);
  rec.points3D[1].xyz.z() = 4;              // one in front, seen twice
  rec.points3D[1].track.push_back({7, 0});  // an element naming no image is ignored
  EXPECT_EQ(ObservedDepthQuantile(rec, 0.98), 4.0);
  EXPECT_EQ(ObservedDepthQuantile(Reconstruction(), 0.5), 0.0);
}

}  // namespace
}  // namespace mvtm
