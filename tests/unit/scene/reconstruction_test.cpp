// Reconstruction helpers against hand-derived values: ObservedDistanceQuantile on a model whose
// points sit at known distances from known cameras, and the same model moved by a similarity.
#include "scene/reconstruction.h"

#include <gtest/gtest.h>

#include <Eigen/Geometry>
#include <limits>

namespace mvtm {
namespace {

// Two cameras looking down +z, at the origin and 2 behind it (identity rotation, world-to-camera
// t = -C), and ten points at z = 1..10 on their common axis, each seen by both: the 20
// distances are 1..10 and 3..12, sorted 1, 2, 3, 3, 4, 4, ..., 10, 10, 11, 12.
Reconstruction Axis(double scale, const Eigen::Vector3d& offset) {
  Reconstruction rec;
  for (uint32_t id : {1u, 2u}) {
    ImageRecord im;
    im.id = id;
    const Eigen::Vector3d c = scale * Eigen::Vector3d(0, 0, -2.0 * (id - 1)) + offset;
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

TEST(Reconstruction, ObservedDistanceQuantileIsTheQuantileOfEveryObservation) {
  const Reconstruction rec = Axis(1, Eigen::Vector3d::Zero());
  // Index round(q·19) of the sorted distances (base/stats Percentile).
  EXPECT_EQ(ObservedDistanceQuantile(rec, 0.0), 1.0);
  EXPECT_EQ(ObservedDistanceQuantile(rec, 0.5), 7.0);
  EXPECT_EQ(ObservedDistanceQuantile(rec, 0.89), 10.0);
  EXPECT_EQ(ObservedDistanceQuantile(rec, 0.98), 12.0);
  EXPECT_EQ(SceneFarEnd(rec), 12.0);
  EXPECT_EQ(ObservedDistanceQuantile(rec, std::numeric_limits<double>::quiet_NaN()), 1.0);
  // Seen from the side, a point's distance is not its depth: a point 3 to the side of the first
  // camera at z = 4 is 5 away.
  Reconstruction side = rec;
  side.points3D = {{1, side.points3D[4]}};
  side.points3D[1].xyz = {3, 0, 4};
  side.points3D[1].track = {{1, 0}};
  EXPECT_EQ(ObservedDistanceQuantile(side, 0.5), 5.0);
  // Scaled by 0.2 at UTM coordinates: the same quantile, scaled.
  const Reconstruction moved = Axis(0.2, Eigen::Vector3d(451000, 5410000, 120));
  EXPECT_NEAR(ObservedDistanceQuantile(moved, 0.5), 1.4, 1e-9);
  EXPECT_NEAR(SceneFarEnd(moved), 2.4, 1e-9);
}

TEST(Reconstruction, ObservedDistanceQuantileLeavesOutWhatNoCameraSeesInFront) {
  Reconstruction rec = Axis(1, Eigen::Vector3d::Zero());
  for (auto& [k, p] : rec.points3D) p.xyz.z() = -2 - p.xyz.z();  // every point behind both
  EXPECT_EQ(ObservedDistanceQuantile(rec, 0.98), 0.0);
  rec.points3D[1].xyz.z() = 4;              // one in front of both: 4 and 6 away
  rec.points3D[1].track.push_back({7, 0});  // an element naming no image is ignored
  EXPECT_EQ(ObservedDistanceQuantile(rec, 0.98), 6.0);
  EXPECT_EQ(ObservedDistanceQuantile(rec, 0.0), 4.0);
  EXPECT_EQ(ObservedDistanceQuantile(Reconstruction(), 0.5), 0.0);
}

}  // namespace
}  // namespace mvtm
