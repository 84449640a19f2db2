// Camera models: projection round trips, the GL projection against the pinhole formula, errors.
#include "camera/camera.h"

#include <gtest/gtest.h>

#include "base/error.h"

namespace mvtm {
namespace {

Camera Kitti() { return ParseCameraSpec("PINHOLE 1241 376 718.856 718.856 607.1928 185.2157"); }

TEST(Camera, ProjectUnprojectRoundTrip) {
  Camera c = Kitti();
  Eigen::Vector3d x(1.5, -0.7, 12.0);
  Eigen::Vector2d p = c.Project(x);
  EXPECT_NEAR(p.x(), 718.856 * 1.5 / 12 + 607.1928, 1e-12);
  EXPECT_LT((c.Unproject(p, 12.0) - x).norm(), 1e-12);
}

TEST(Camera, GlProjectionMapsPixelsToNdc) {
  Camera c = Kitti();
  const double n = 0.1, f = 500;
  Eigen::Matrix4d P = c.GlProjection(n, f);
  for (Eigen::Vector3d x : {Eigen::Vector3d(1.5, -0.7, 12.0), Eigen::Vector3d(-3, 2, 0.5),
                            Eigen::Vector3d(0, 0, 499)}) {
    Eigen::Vector2d px = c.Project(x);
    Eigen::Vector4d eye(x.x(), -x.y(), -x.z(), 1);  // camera → OpenGL eye axes
    Eigen::Vector4d clip = P * eye;
    Eigen::Vector3d ndc = clip.head<3>() / clip.w();
    EXPECT_NEAR(ndc.x(), 2 * px.x() / 1241 - 1, 1e-12);
    EXPECT_NEAR(ndc.y(), 1 - 2 * px.y() / 376, 1e-12);  // +1 = top row
    // Depth: the standard perspective mapping of z between near (−1) and far (+1).
    double expect_z = (f + n) / (f - n) - 2 * f * n / ((f - n) * x.z());
    EXPECT_NEAR(ndc.z(), expect_z, 1e-12);
  }
}

TEST(Camera, DistortedModelsCannotProject) {
  Camera c = ParseCameraSpec("OPENCV 640 480 500 500 320 240 0.1 0.01 0 0");
  try {
    c.K();
    FAIL();
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("run colmap image_undistorter"), std::string::npos);
  }
}

TEST(Camera, SpecErrors) {
  EXPECT_THROW(ParseCameraSpec("PINHOLE 10 10 1 2 3"), UsageError);  // 3 of 4 params
  EXPECT_THROW(ParseCameraSpec("FISHY 10 10 1"), UsageError);
  EXPECT_THROW(ParseCameraSpec("PINHOLE 0 10 1 1 1 1"), UsageError);
  Camera s = ParseCameraSpec("SIMPLE_PINHOLE 100 50 80 50 25");
  EXPECT_EQ(s.fy(), 80);
  EXPECT_EQ(s.cy(), 25);
}

TEST(Camera, ScaledKeepsPixelCentreConvention) {
  Camera c = Kitti();
  Camera h = c.Scaled(620, 188);
  // A point at the image's right edge stays at the right edge.
  Eigen::Vector3d x = c.Unproject({1241, 376}, 10);
  Eigen::Vector2d p = h.Project(x);
  EXPECT_NEAR(p.x(), 620, 1e-9);
  EXPECT_NEAR(p.y(), 188, 1e-9);
}

}  // namespace
}  // namespace mvtm
