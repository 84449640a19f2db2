// libcore/stereo against hand-derived truth: textured planes at known depths seen by cameras
// with known baselines (images computed by intersecting each pixel's ray with the plane, sharing
// nothing with the sweep), the homography of a plane, and the hard cases (no baseline, planes
// through a camera centre, a textureless image, no neighbours, no points).
#include "stereo/plane_sweep.h"

#include <gtest/gtest.h>

#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <limits>

#include "stereo/neighbours.h"

namespace mvtm {
namespace {

Camera Cam(int w = 96, int h = 64, double f = 60) {
  return ParseCameraSpec("PINHOLE " + std::to_string(w) + " " + std::to_string(h) + " " +
                         std::to_string(f) + " " + std::to_string(f) + " " +
                         std::to_string(w / 2.0) + " " + std::to_string(h / 2.0));
}

// A camera at `c` with the identity rotation (looking down +z, y down).
Rigid3d At(const Eigen::Vector3d& c) { return Rigid3d(Eigen::Quaterniond::Identity(), -c); }

// Value noise: smooth, non-periodic (bilinear between pseudo-random values on a 0.2-unit lattice),
// like asphalt or foliage rather than a repeating pattern that would alias the match.
double Lattice(long i, long j) {
  uint64_t h = uint64_t(i) * 0x9E3779B97F4A7C15ull ^ uint64_t(j) * 0xC2B2AE3D27D4EB4Full;
  h ^= h >> 29;
  h *= 0xBF58476D1CE4E5B9ull;
  h ^= h >> 32;
  return double(h % 1000) / 999.0;
}
double Texture(double a, double b) {
  const double u = a / 0.2, v = b / 0.2;
  const long i = long(std::floor(u)), j = long(std::floor(v));
  const double fu = u - double(i), fv = v - double(j);
  const double n = (1 - fu) * ((1 - fv) * Lattice(i, j) + fv * Lattice(i, j + 1)) +
                   fu * ((1 - fv) * Lattice(i + 1, j) + fv * Lattice(i + 1, j + 1));
  return 40 + 180 * n;
}

// The image a camera sees of the plane n·X = d (world), textured by Texture of two in-plane
// coordinates; 0 where the ray misses the plane (it never does in these tests).
cv::Mat See(const Camera& cam, const Rigid3d& w2c, const Eigen::Vector3d& n, double d) {
  cv::Mat im(int(cam.height), int(cam.width), CV_32F, cv::Scalar(0));
  const Eigen::Matrix3d Rt = w2c.R().transpose();
  const Eigen::Vector3d C = w2c.Centre();
  const Eigen::Vector3d u = n.unitOrthogonal(), v = n.cross(u);
  for (int y = 0; y < im.rows; ++y)
    for (int x = 0; x < im.cols; ++x) {
      const Eigen::Vector3d ray = Rt * cam.Unproject({x + 0.5, y + 0.5}, 1.0);
      const double t = (d - n.dot(C)) / n.dot(ray);
      if (!(t > 0)) continue;
      const Eigen::Vector3d X = C + t * ray;
      im.at<float>(y, x) = float(Texture(u.dot(X), v.dot(X)));
    }
  return im;
}

// The view of the plane n·X = d (world) from a camera at (bx, 0, 0) looking down +z.
StereoView ViewAt(const Camera& cam, double bx, const Eigen::Vector3d& n, double d) {
  return {cam, At({bx, 0, 0}), See(cam, At({bx, 0, 0}), n, d)};
}

// Relative depth error statistics over the pixels with a depth.
struct Score {
  double median_rel = 1e9, valid = 0;
};
Score Compare(const DepthMap& m, const std::function<double(int, int)>& truth) {
  std::vector<double> rel;
  for (int y = 0; y < m.depth.height; ++y)
    for (int x = 0; x < m.depth.width; ++x)
      if (std::isfinite(m.depth.at(x, y)))
        rel.push_back(std::abs(m.depth.at(x, y) / truth(x, y) - 1));
  Score s;
  s.valid = double(rel.size()) / double(m.depth.pixels());
  if (rel.empty()) return s;
  std::nth_element(rel.begin(), rel.begin() + long(rel.size() / 2), rel.end());
  s.median_rel = rel[rel.size() / 2];
  return s;
}

TEST(PlaneSweep, HomographyMapsPlanePointsToTheirNeighbourPixels) {
  StereoView a{Cam(), At({0, 0, 0}), {}},
      b{Cam(),
        Rigid3d(Eigen::Quaterniond(Eigen::AngleAxisd(0.1, Eigen::Vector3d::UnitY())),
                {-0.7, 0.1, 0.2}),
        {}};
  const Eigen::Vector3d n = Eigen::Vector3d(0.2, -0.3, 1).normalized();
  const double d = 6.0;
  const Eigen::Matrix3d H = PlaneHomography(a, b, n, d);
  for (const auto& px :
       {Eigen::Vector2d(3.5, 7.5), Eigen::Vector2d(50, 31), Eigen::Vector2d(90.5, 60.5)}) {
    const Eigen::Vector3d r = a.camera.Unproject(px, 1.0);
    const Eigen::Vector3d X =
        r * (d / n.dot(r));  // on the plane, reference coordinates = world here
    const Eigen::Vector2d expect = b.camera.Project(b.world_to_camera * X);
    const Eigen::Vector3d h = H * Eigen::Vector3d(px.x(), px.y(), 1);
    EXPECT_NEAR(h.x() / h.z(), expect.x(), 1e-9);
    EXPECT_NEAR(h.y() / h.z(), expect.y(), 1e-9);
  }
}

TEST(PlaneSweep, FrontoParallelWallAtKnownDepth) {
  const Eigen::Vector3d n(0, 0, 1);
  const double Z = 8.0;
  const Camera cam = Cam();
  const StereoView ref = ViewAt(cam, 0, n, Z);
  std::vector<StereoView> nbs;
  for (double bx : {-0.6, 0.6, 1.2}) nbs.push_back(ViewAt(cam, bx, n, Z));
  const DepthMap m = SweepDepth(ref, nbs, {MakeFrontoSweep(3, 30, 64)}, PlaneSweepOptions());
  const Score s = Compare(m, [&](int, int) { return Z; });
  std::printf("[fronto wall] valid %.3f, median relative error %.2e\n", s.valid, s.median_rel);
  // Hand-derived coverage: the 3 border rows top and bottom (window not inside the image) and the
  // ~8 left columns that only one neighbour sees (k = 2) have no depth: about 83 % remain.
  EXPECT_GT(s.valid, 0.78);
  EXPECT_LT(s.median_rel, 0.005);  // plane spacing at 8 is ~2.3 %: the parabola refines it
}

TEST(PlaneSweep, PerPixelRefinementIsNotBoundByThePlaneSpacing) {
  // A wall at 8 between two planes of a coarse sweep (7 planes from 3 to 30, evenly in inverse
  // depth: at 8 the planes are ~40 % of the depth apart). The parabola through three planes that
  // far apart misses by percents (measured 4.9 %); refined on its own plane at 4 sub-steps per
  // spacing (~10 % of the depth) the depth is within 0.5 % (measured 0.34 %).
  const Eigen::Vector3d n(0, 0, 1);
  const double Z = 8.0;
  const Camera cam = Cam();
  const StereoView ref = ViewAt(cam, 0, n, Z);
  std::vector<StereoView> nbs;
  for (double bx : {-0.6, 0.6, 1.2}) nbs.push_back(ViewAt(cam, bx, n, Z));
  PlaneSweepOptions o;
  o.min_margin = 0;  // few planes: keep every match, the test is about precision
  o.refine = 0;
  const Score coarse =
      Compare(SweepDepth(ref, nbs, {MakeFrontoSweep(3, 30, 7)}, o), [&](int, int) { return Z; });
  o.refine = 4;
  const Score fine =
      Compare(SweepDepth(ref, nbs, {MakeFrontoSweep(3, 30, 7)}, o), [&](int, int) { return Z; });
  std::printf("[refinement] median relative error %.2e (parabola only %.2e), valid %.3f\n",
              fine.median_rel, coarse.median_rel, fine.valid);
  EXPECT_GT(coarse.median_rel, 0.02);
  EXPECT_LT(fine.median_rel, 0.005);
  EXPECT_GT(fine.valid, 0.7);
}

TEST(PlaneSweep, GroundPlaneFoundByTheGroundSweep) {
  // Ground y = 1.5 below cameras looking level along +z; cameras move forward (like a car).
  const Eigen::Vector3d n(0, 1, 0);
  const double h = 1.5;
  const Camera cam = Cam();
  StereoView ref{cam, At({0, 0, 0}), See(cam, At({0, 0, 0}), n, h)};
  std::vector<StereoView> nbs;
  for (double bz : {-2.0, -1.0, 1.0, 2.0})
    nbs.push_back({cam, At({0, 0, bz}), See(cam, At({0, 0, bz}), n, h)});
  PlaneSweepOptions o;
  const DepthMap m = SweepDepth(ref, nbs, {MakeOffsetSweep("ground", n, 0.5, 3.0, 32)}, o);
  // Truth: the ray through pixel row y meets y_cam = h at z = h·f/(y + 0.5 − cy); upper half has no
  // ground.
  const Score s = Compare(m, [&](int, int y) { return h * cam.fy() / (y + 0.5 - cam.cy()); });
  std::printf("[ground] valid %.3f, median relative error %.2e\n", s.valid, s.median_rel);
  // The lower half sees the ground; its rows near the horizon have almost no parallax under
  // forward motion (ambiguous: rejected by the margin), the last 3 rows are border.
  EXPECT_GT(s.valid, 0.2);
  EXPECT_LT(s.median_rel, 0.02);  // 32 planes 5.4 % apart in offset, refined by the parabola
  for (int y = 0; y < int(cam.cy()); ++y)
    for (int x = 0; x < int(cam.width); ++x)
      ASSERT_TRUE(std::isinf(m.depth.at(x, y))) << x << "," << y;
}

TEST(PlaneSweep, TexturelessImageGivesNoDepth) {
  const Camera cam = Cam();
  cv::Mat flat(int(cam.height), int(cam.width), CV_32F, cv::Scalar(100));
  StereoView ref{cam, At({0, 0, 0}), flat};
  std::vector<StereoView> nbs{{cam, At({0.5, 0, 0}), flat.clone()},
                              {cam, At({-0.5, 0, 0}), flat.clone()}};
  const DepthMap m = SweepDepth(ref, nbs, {MakeFrontoSweep(1, 50, 16)}, PlaneSweepOptions());
  for (size_t i = 0; i < m.depth.data.size(); ++i) {
    ASSERT_TRUE(std::isinf(m.depth.data[i]));
    ASSERT_EQ(m.confidence.data[i], 0.f);
  }
}

TEST(PlaneSweep, NoNeighboursGivesNoDepth) {
  const Camera cam = Cam();
  StereoView ref{cam, At({0, 0, 0}), See(cam, At({0, 0, 0}), {0, 0, 1}, 5)};
  const DepthMap m = SweepDepth(ref, {}, {MakeFrontoSweep(1, 50, 16)}, PlaneSweepOptions());
  EXPECT_EQ(m.depth.width, int(cam.width));
  for (float z : m.depth.data) ASSERT_TRUE(std::isinf(z));
}

TEST(PlaneSweep, FamiliesOfNoneOrOnePlaneAreHarmless) {
  // An empty family finds nothing; a family of one plane (at the wall, z = 8) has no spacing to
  // refine within: its pixels keep that plane's depth exactly.
  const Eigen::Vector3d n(0, 0, 1);
  const Camera cam = Cam();
  const StereoView ref = ViewAt(cam, 0, n, 8);
  std::vector<StereoView> nbs;
  for (double bx : {-0.6, 0.6}) nbs.push_back(ViewAt(cam, bx, n, 8));
  SweepFamily empty, one;
  empty.name = "empty";
  one.name = "one";
  one.offsets = {8.0};
  PlaneSweepOptions o;
  o.min_margin = 0;  // one plane: its margin over the family's mean is 0
  for (float z : SweepDepth(ref, nbs, {empty}, o).depth.data) ASSERT_TRUE(std::isinf(z));
  size_t found = 0;
  for (float z : SweepDepth(ref, nbs, {empty, one}, o).depth.data) {
    if (std::isinf(z)) continue;
    ASSERT_FLOAT_EQ(z, 8.0f);
    ++found;
  }
  EXPECT_GT(found, cam.width * cam.height / 2);
}

TEST(PlaneSweep, PlanesThroughACameraCentreStayFinite) {
  // Facade planes x = d, including d = 0 (through the reference centre) and d = 0.6 (through the
  // neighbour's centre): no NaN, and the wall at x = -2 is still found.
  const Eigen::Vector3d n(1, 0, 0);
  const Camera cam = Cam();
  // Looking forward and to the left (world −x), where the wall is.
  const Rigid3d r =
      Rigid3d(Eigen::Quaterniond(Eigen::AngleAxisd(0.6, Eigen::Vector3d::UnitY())), {0, 0, 0});
  auto view = [&](const Eigen::Vector3d& c) {
    Rigid3d p(r.q, -(r.q * c));
    return StereoView{cam, p, See(cam, p, n, -2.0)};
  };
  StereoView ref = view({0, 0, 0});
  std::vector<StereoView> nbs{view({0.6, 0, 0.5}), view({0, 0, 1.0})};
  SweepFamily f = MakeOffsetSweep("facade", r.R() * n, -3.0, 0.6, 37);  // contains 0 and 0.6
  ASSERT_NE(std::find(f.offsets.begin(), f.offsets.end(), 0.0), f.offsets.end());
  const DepthMap m = SweepDepth(ref, nbs, {f}, PlaneSweepOptions());
  size_t finite = 0;
  for (size_t i = 0; i < m.depth.data.size(); ++i) {
    ASSERT_FALSE(std::isnan(m.depth.data[i]));
    ASSERT_FALSE(std::isnan(m.confidence.data[i]));
    finite += std::isfinite(m.depth.data[i]);
  }
  EXPECT_GT(double(finite) / double(m.depth.data.size()), 0.25);
  // Truth: the ray of pixel (x, y) meets the world plane x = −2 at z = −2 / (Rᵀ r).x, r = K⁻¹(x, y,
  // 1).
  const Eigen::Matrix3d Rt = r.R().transpose();
  const Score s = Compare(m, [&](int x, int y) {
    return -2.0 / (Rt * cam.Unproject({x + 0.5, y + 0.5}, 1.0)).x();
  });
  std::printf("[facade] valid %.3f, median relative error %.2e\n", s.valid, s.median_rel);
  EXPECT_LT(s.median_rel, 0.01);
}

TEST(Neighbours, NoBaselineNoCoverageAndTooWideAnglesAreSkipped) {
  std::vector<Rigid3d> poses;
  for (int i = 0; i < 8; ++i) poses.push_back(At({0, 0, double(i)}));
  poses[3] = poses[4];  // a stop: image 3 has no baseline to image 4
  poses[6] =
      Rigid3d(Eigen::Quaterniond(Eigen::AngleAxisd(1.2, Eigen::Vector3d::UnitY())), poses[6].t);
  std::vector<Camera> cams(poses.size(), Cam());
  NeighbourOptions o;
  o.count = 4;
  const auto nb = SelectStereoNeighbours(poses, cams, 4, {}, o);
  // The nearest first (5, ahead), then alternately behind and ahead, nearest first on each side;
  // 3: no baseline; 6: turned 69 degrees.
  EXPECT_EQ(nb, (std::vector<size_t>{5, 2, 7, 1}));
  // Coverage: points behind every camera but the reference's are never seen by neighbours.
  const auto none = SelectStereoNeighbours(poses, cams, 0, {Eigen::Vector3d(0, 0, 0.5)}, o);
  EXPECT_TRUE(none.empty());
  EXPECT_DOUBLE_EQ(MedianSpacing(poses), 1.0);
}

TEST(Neighbours, AnotherDriveAlongTheSameRoadIsANeighbour) {
  // Drive A at z = 0, 2, 4, ...; drive B one unit to the side, 0.8 further along. From A's image
  // 2 (z = 4) the nearest centres are B's image 2 (ahead, 1.28 away) and B's image 1 (behind,
  // 1.56), then A's 3 (ahead, 2) and A's 1 (behind, 2), whatever their order in the list.
  std::vector<Rigid3d> poses;
  for (int i = 0; i < 8; ++i) poses.push_back(At({0, 0, 2.0 * i}));
  for (int i = 0; i < 8; ++i) poses.push_back(At({1, 0, 2.0 * i + 0.8}));
  std::vector<Camera> cams(poses.size(), Cam());
  NeighbourOptions o;
  o.count = 4;
  EXPECT_EQ(SelectStereoNeighbours(poses, cams, 2, {}, o), (std::vector<size_t>{10, 9, 3, 1}));
  o.count = 2;  // one from each side
  EXPECT_EQ(SelectStereoNeighbours(poses, cams, 2, {}, o), (std::vector<size_t>{10, 9}));
  // The first image has nothing behind it: the rest come from ahead, nearest first (B0 at 1.28).
  o.count = 3;
  EXPECT_EQ(SelectStereoNeighbours(poses, cams, 0, {}, o), (std::vector<size_t>{8, 1, 9}));
}

TEST(Neighbours, SweepFamiliesComeFromThePointsAndNeedSome) {
  Eigen::Vector3d down, side;
  std::vector<Rigid3d> poses{At({0, 0, 0}), At({0, 0, 1}), At({0, 0, 2})};
  DriveAxes(poses, down, side);
  EXPECT_NEAR((down - Eigen::Vector3d(0, 1, 0)).norm(), 0, 1e-12);
  EXPECT_NEAR(std::abs(side.x()), 1, 1e-12);
  EXPECT_TRUE(SweepFamiliesFor(poses[0], {}, down, side, 16).empty());
  std::vector<Eigen::Vector3d> pts;
  for (int i = 0; i < 50; ++i) pts.push_back({-3 + 0.1 * i, 1.5, 4 + 0.3 * i});
  const auto fam = SweepFamiliesFor(poses[0], pts, down, side, 16);
  ASSERT_EQ(fam.size(), 3u);
  EXPECT_EQ(fam[0].name, "fronto");
  EXPECT_LT(fam[0].offsets.front(), 4.0);  // nearer than the nearest point
  EXPECT_GT(fam[0].offsets.back(), 18.7);  // farther than the farthest
  EXPECT_EQ(fam[1].name, "ground");
  EXPECT_LE(fam[1].offsets.front(), 1.5);
  EXPECT_GE(fam[1].offsets.back(), 1.5);
}

}  // namespace
}  // namespace mvtm
