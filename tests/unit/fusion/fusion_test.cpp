// Fusion tests on analytic scenes: every depth map is a per-pixel ray intersection with planes
// and a box, computed here in double (sharing nothing with libcore/fusion), then stored as float
// like densify's output. The fused mesh is judged against the true surfaces.
#include "fusion/fusion.h"

#include <gtest/gtest.h>

#include <Eigen/Geometry>
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <limits>
#include <map>
#include <set>
#include <utility>
#include <vector>

#include "base/error.h"

namespace mvtm {
namespace {

constexpr double kInf = std::numeric_limits<double>::infinity();

struct Plane {  // n·X = d, |n| = 1
  Eigen::Vector3d n;
  double d;
};
struct Box {
  Eigen::Vector3d lo, hi;
};
struct Scene {
  std::vector<Plane> planes;
  std::vector<Box> boxes;
};

// World axes as the camera's at rest: x right, y down, z forward; "up" is -y.
Rigid3d LookAt(const Eigen::Vector3d& centre, const Eigen::Vector3d& target) {
  const Eigen::Vector3d z = (target - centre).normalized();
  const Eigen::Vector3d x = z.cross(Eigen::Vector3d(0, -1, 0)).normalized();
  const Eigen::Vector3d y = z.cross(x);
  Eigen::Matrix3d r;
  r.row(0) = x;
  r.row(1) = y;
  r.row(2) = z;
  return Rigid3d(Eigen::Quaterniond(r), -r * centre);
}

double RayBox(const Eigen::Vector3d& o, const Eigen::Vector3d& d, const Box& b) {
  double t0 = 0, t1 = kInf;
  for (int a = 0; a < 3; ++a) {
    const double u = (b.lo[a] - o[a]) / d[a], v = (b.hi[a] - o[a]) / d[a];
    t0 = std::max(t0, std::min(u, v));
    t1 = std::min(t1, std::max(u, v));
  }
  return t0 <= t1 && t0 > 0 ? t0 : kInf;
}

// Depth z of the first surface along each pixel's ray (the ray's camera z component is 1, so the
// ray parameter is z itself).
DepthView Render(const Scene& s, const Camera& cam, const Rigid3d& pose) {
  DepthView v{
      cam, pose, Image(static_cast<int>(cam.width), static_cast<int>(cam.height), 1, 32), {}};
  const Eigen::Matrix3d r_t = pose.R().transpose();
  const Eigen::Vector3d o = pose.Centre();
  const double fx = cam.params[0], fy = cam.params[1], cx = cam.params[2], cy = cam.params[3];
  for (int y = 0; y < v.depth.height; ++y) {
    for (int x = 0; x < v.depth.width; ++x) {
      const Eigen::Vector3d d = r_t * Eigen::Vector3d((x + 0.5 - cx) / fx, (y + 0.5 - cy) / fy, 1);
      double best = kInf;
      for (const Plane& p : s.planes) {
        const double t = (p.d - p.n.dot(o)) / p.n.dot(d);
        if (t > 0) best = std::min(best, t);
      }
      for (const Box& b : s.boxes) best = std::min(best, RayBox(o, d, b));
      v.depth.at(x, y) = static_cast<float>(best);
    }
  }
  return v;
}

double BoxDistance(const Eigen::Vector3d& p, const Box& b) {
  const Eigen::Vector3d c = (b.lo + b.hi) / 2, h = (b.hi - b.lo) / 2;
  const Eigen::Vector3d q = (p - c).cwiseAbs() - h;
  return std::abs(q.cwiseMax(0.0).norm() + std::min(q.maxCoeff(), 0.0));
}

double SurfaceDistance(const Scene& s, const Eigen::Vector3d& p) {
  double best = kInf;
  for (const Plane& pl : s.planes) best = std::min(best, std::abs(pl.n.dot(p) - pl.d));
  for (const Box& b : s.boxes) best = std::min(best, BoxDistance(p, b));
  return best;
}

Camera MakeCamera(int w, int h, double f) {
  Camera c;
  c.model = CameraModel::kPinhole;
  c.width = w;
  c.height = h;
  c.params = {f, f, w / 2.0, h / 2.0};
  return c;
}

// A road: the ground 1.5 below the cameras (y = 1.5) and a facade at x = 3; cameras drive along
// +z with spacing 1, looking 10 ahead and slightly down. 613×185 (KITTI at half size).
Scene RoadScene() { return {{{{0, 1, 0}, 1.5}, {{1, 0, 0}, 3.0}}, {}}; }
std::vector<DepthView> RoadViews(const Scene& s, int n) {
  std::vector<DepthView> views;
  const Camera cam = MakeCamera(613, 185, 360);
  for (int i = 0; i < n; ++i) {
    const Eigen::Vector3d c(0, 0, i);
    views.push_back(Render(s, cam, LookAt(c, c + Eigen::Vector3d(0.5, 1.0, 10))));
  }
  return views;
}

// A box on the ground seen from seven cameras on an arc around it (±69°), so that each side face
// is seen by three cameras, which the strict consistency filter needs (min_agree = 2).
Scene BoxScene() { return {{{{0, 1, 0}, 1.0}}, {{{-0.5, 0.0, 4.5}, {0.5, 1.0, 5.5}}}}; }
std::vector<DepthView> BoxViews(const Scene& s) {
  std::vector<DepthView> views;
  const Camera cam = MakeCamera(320, 240, 300);
  const Eigen::Vector3d target(0, 0.5, 5);
  for (int i = -3; i <= 3; ++i) {
    const double a = 0.4 * i;
    const Eigen::Vector3d c = target + 4.0 * Eigen::Vector3d(std::sin(a), -0.5, -std::cos(a));
    views.push_back(Render(s, cam, LookAt(c, target)));
  }
  return views;
}

// Distance to the nearest line where two surfaces meet: the box's 12 edges (its bottom edges are
// where it meets the ground) or the road's ground–facade line.
double SegmentDistance(const Eigen::Vector3d& p, const Eigen::Vector3d& a,
                       const Eigen::Vector3d& b) {
  const double t = std::clamp((p - a).dot(b - a) / (b - a).squaredNorm(), 0.0, 1.0);
  return (p - (a + t * (b - a))).norm();
}
double EdgeDistance(const Scene& s, const Eigen::Vector3d& p) {
  if (s.boxes.empty() && s.planes.size() == 1) return kInf;          // the wall
  if (s.boxes.empty()) return std::hypot(p.x() - 3.0, p.y() - 1.5);  // the road
  const Box& b = s.boxes[0];
  double best = kInf;
  for (int a = 0; a < 3; ++a) {
    const int u = (a + 1) % 3, v = (a + 2) % 3;
    for (int k = 0; k < 4; ++k) {
      Eigen::Vector3d e0, e1;
      e0[u] = e1[u] = (k & 1) ? b.hi[u] : b.lo[u];
      e0[v] = e1[v] = (k & 2) ? b.hi[v] : b.lo[v];
      e0[a] = b.lo[a];
      e1[a] = b.hi[a];
      best = std::min(best, SegmentDistance(p, e0, e1));
    }
  }
  return best;
}

// Vertices on the mesh's border: on an edge that only one face uses.
std::vector<Eigen::Vector3d> BorderVertices(const Mesh& m) {
  std::map<std::pair<uint32_t, uint32_t>, int> uses;
  for (const auto& f : m.faces) {
    for (int k = 0; k < 3; ++k) {
      ++uses[std::minmax(f[k], f[(k + 1) % 3])];
    }
  }
  std::set<uint32_t> border;
  for (const auto& [e, n] : uses) {
    if (n == 1) border.insert({e.first, e.second});
  }
  std::vector<Eigen::Vector3d> out;
  for (uint32_t i : border) out.push_back(m.vertices[i]);
  return out;
}

// Vertex distance to the true surface, in voxels: over all vertices and over the interior ones,
// more than a truncation (3 voxels) from any edge of the scene (so every ray that updates a
// voxel hit the same plane) and from the mesh's border (so rays came from all sides).
struct Distances {
  double max = 0, mean = 0, max_interior = 0;
  size_t interior = 0;
};
Distances MeshDistances(const Scene& s, const Mesh& m, double voxel) {
  const std::vector<Eigen::Vector3d> border = BorderVertices(m);
  Distances d;
  for (const Eigen::Vector3d& v : m.vertices) {
    const double e = SurfaceDistance(s, v) / voxel;
    d.max = std::max(d.max, e);
    d.mean += e;
    if (EdgeDistance(s, v) <= 3 * voxel) continue;
    const bool near_border = std::any_of(border.begin(), border.end(), [&](const auto& b) {
      return (b - v).squaredNorm() <= 9 * voxel * voxel;
    });
    if (near_border) continue;
    d.max_interior = std::max(d.max_interior, e);
    ++d.interior;
  }
  if (!m.vertices.empty()) d.mean /= static_cast<double>(m.vertices.size());
  std::printf(
      "  %zu vertices (%zu interior): distance to truth max %.3f (interior %.3f), "
      "mean %.4f voxels\n",
      m.vertices.size(), d.interior, d.max, d.max_interior, d.mean);
  return d;
}

}  // namespace

// Signed distance with the free side positive: above the ground (y < ground), outside the box.
double SceneSdf(const Scene& s, const Eigen::Vector3d& p) {
  double best = kInf;
  for (const Plane& pl : s.planes) best = std::min(best, pl.d - pl.n.dot(p));
  for (const Box& b : s.boxes) {
    const Eigen::Vector3d q = (p - (b.lo + b.hi) / 2).cwiseAbs() - (b.hi - b.lo) / 2;
    best = std::min(best, q.cwiseMax(0.0).norm() + std::min(q.maxCoeff(), 0.0));
  }
  return best;
}

// Bounds (hand-derived, in voxels).
//  * Interior (see MeshDistances): the TSDF is the projective
//    distance along each ray, exact at the ray's own surface point; a voxel centre sits up to
//    √3/2 voxel off the rays that update it, which at incidence θ shifts its range by
//    ±offset·tan θ, cancelling between rays on either side; OpenVDB places a vertex at the mean of
//    its cell's edge crossings, and a mean of points on a plane stays on the plane. Bound 0.25.
//  * Anywhere: a vertex lies inside a cell that the surface crosses (the mean of crossings on the
//    cell's edges), so within the cell diagonal, √3 ≈ 1.73. Next to a 90° edge the mean of
//    crossings on the two faces cuts the corner by up to √2/2 of a voxel.
constexpr double kInteriorBound = 0.25;
constexpr double kCellDiagonal = 1.7320508075688772;

TEST(Fusion, RoadPlanes) {
  const Scene s = RoadScene();
  const std::vector<DepthView> views = RoadViews(s, 6);
  FusionOptions o;
  o.tsdf.voxel_per_spacing = 0.1;
  o.tsdf.max_depth_spacings = 15;
  const Mesh m = FuseDepthViews(views, o);
  const double voxel = 0.1 * MedianCameraSpacing(views);
  EXPECT_DOUBLE_EQ(voxel, 0.1);
  const Distances d = MeshDistances(s, m, voxel);
  ASSERT_GT(m.faces.size(), 1000u);
  EXPECT_LT(d.max_interior, kInteriorBound);
  EXPECT_LT(d.max, std::sqrt(0.5) + kInteriorBound);  // the concave ground–facade line
  // Both planes are there: vertices on the ground and on the facade.
  size_t ground = 0, facade = 0;
  for (const Eigen::Vector3d& v : m.vertices) {
    ground += std::abs(v.y() - 1.5) < kInteriorBound * voxel;
    facade += std::abs(v.x() - 3.0) < kInteriorBound * voxel;
  }
  EXPECT_GT(ground, 2000u);
  EXPECT_GT(facade, 2000u);
}

TEST(Fusion, BoxOnGround) {
  const Scene s = BoxScene();
  const std::vector<DepthView> views = BoxViews(s);
  FusionOptions o;
  o.tsdf.voxel_per_spacing = 0.03;
  o.tsdf.max_depth_spacings = 5;  // the box and the ground around it (depth < 8)
  const Mesh m = FuseDepthViews(views, o);
  const double voxel = 0.03 * MedianCameraSpacing(views);
  const Distances d = MeshDistances(s, m, voxel);
  EXPECT_LT(d.max_interior, kInteriorBound);
  EXPECT_LT(d.max, kCellDiagonal);
  // The box's top (y = 0), front (z = 4.5) and both sides (x = ±0.5) are meshed.
  const Box& b = s.boxes[0];
  size_t top = 0, front = 0, left = 0, right = 0;
  for (const Eigen::Vector3d& v : m.vertices) {
    if (BoxDistance(v, b) > kInteriorBound * voxel) continue;
    top += std::abs(v.y() - b.lo.y()) < kInteriorBound * voxel;
    front += std::abs(v.z() - b.lo.z()) < kInteriorBound * voxel;
    left += std::abs(v.x() - b.lo.x()) < kInteriorBound * voxel;
    right += std::abs(v.x() - b.hi.x()) < kInteriorBound * voxel;
  }
  EXPECT_GT(top, 100u);
  EXPECT_GT(front, 100u);
  EXPECT_GT(left, 20u);
  EXPECT_GT(right, 20u);
  // Faces wind counter-clockwise seen from the free side: the face normal agrees with the
  // gradient of the true signed distance (central differences at the face's centroid).
  size_t outward = 0;
  for (const auto& f : m.faces) {
    const Eigen::Vector3d a = m.vertices[f[0]], b1 = m.vertices[f[1]], c = m.vertices[f[2]];
    const Eigen::Vector3d g = (a + b1 + c) / 3;
    Eigen::Vector3d grad;
    for (int k = 0; k < 3; ++k) {
      const Eigen::Vector3d h = Eigen::Vector3d::Unit(k) * 1e-4;
      grad[k] = SceneSdf(s, g + h) - SceneSdf(s, g - h);
    }
    outward += (b1 - a).cross(c - a).dot(grad) > 0;
  }
  EXPECT_GT(outward, m.faces.size() * 999 / 1000) << "of " << m.faces.size();
  EXPECT_TRUE(m.has_normals());
}

// The volume used directly gives FuseDepthViews' mesh; reports the time per 613×185 depth map.
TEST(Fusion, VolumeMatchesFuseAndTiming) {
  const Scene s = RoadScene();
  const std::vector<DepthView> views = RoadViews(s, 6);
  FusionOptions o;
  o.tsdf.max_depth_spacings = 15;
  const Mesh fused = FuseDepthViews(views, o);
  std::vector<Image> filtered = FilterConsistentDepth(views, o.consistency);
  TsdfVolume volume(MeanCameraCentre(views), 0.1 * MedianCameraSpacing(views), 3);
  const auto t0 = std::chrono::steady_clock::now();
  for (size_t i = 0; i < views.size(); ++i) {
    volume.Integrate({views[i].camera, views[i].world_to_camera, filtered[i], {}}, 15.0);
  }
  const auto t1 = std::chrono::steady_clock::now();
  const Mesh m = volume.ExtractMesh();
  const auto t2 = std::chrono::steady_clock::now();
  const double ms = std::chrono::duration<double, std::milli>(t1 - t0).count();
  std::printf("  integrate %.1f ms per 613x185 depth map, %zu active voxels, mesh %.1f ms\n",
              ms / static_cast<double>(views.size()), volume.ActiveVoxels(),
              std::chrono::duration<double, std::milli>(t2 - t1).count());
  EXPECT_EQ(m.vertices.size(), fused.vertices.size());
  EXPECT_EQ(m.faces, fused.faces);
  EXPECT_GT(volume.ActiveVoxels(), m.vertices.size());
}

// A slightly tilted wall 6 ahead of cameras 0.5 apart along x, 160×120.
Scene WallScene() { return {{{Eigen::Vector3d(0.1, 0, 1).normalized(), 6.0}}, {}}; }
std::vector<DepthView> WallViews(const Scene& s, int n) {
  std::vector<DepthView> views;
  for (int i = 0; i < n; ++i) {
    const Eigen::Vector3d c(0.5 * i, 0, 0);
    views.push_back(Render(s, MakeCamera(160, 120, 120), LookAt(c, c + Eigen::Vector3d(0, 0, 1))));
  }
  return views;
}

// Where pixel (x, y) of view i lands in view j, written out from the pose (not via Camera).
Eigen::Vector2d Reproject(const std::vector<DepthView>& v, size_t i, size_t j, int x, int y) {
  const Camera& c = v[i].camera;
  const double z = v[i].depth.at(x, y);
  const Eigen::Vector3d xi((x + 0.5 - c.params[2]) / c.params[0] * z,
                           (y + 0.5 - c.params[3]) / c.params[1] * z, z);
  const Eigen::Vector3d xw = v[i].world_to_camera.Inverse() * xi;
  const Eigen::Vector3d xj = v[j].world_to_camera * xw;
  const Camera& cj = v[j].camera;
  return {cj.params[0] * xj.x() / xj.z() + cj.params[2],
          cj.params[1] * xj.y() / xj.z() + cj.params[3]};
}
// 1 inside view j's image by more than a pixel, 0 outside by more than a pixel, -1 in between.
int Inside(const DepthView& j, const Eigen::Vector2d& p) {
  const double w = j.depth.width, h = j.depth.height;
  if (p.x() > 1 && p.y() > 1 && p.x() < w - 1 && p.y() < h - 1) return 1;
  if (p.x() < -1 || p.y() < -1 || p.x() > w + 1 || p.y() > h + 1) return 0;
  return -1;
}

TEST(Consistency, KeepsWhatThreeViewsSeeAndDropsTheRest) {
  // Strict (every pixel needs min_agree = 2 others): kept iff views 1 and 2 both see it.
  // Witnessed (the default): view j can confirm where its depth reaches the point; on a bare
  // wall every view that sees the point does, so a pixel is kept iff at least one other view
  // sees it (the wall's part that view 2 has left behind is kept on view 1's word alone).
  const Scene s = WallScene();
  const std::vector<DepthView> views = WallViews(s, 3);
  ConsistencyOptions strict;
  strict.witnessed = false;
  const std::vector<Image> f = FilterConsistentDepth(views, strict);
  const std::vector<Image> w = FilterConsistentDepth(views, {});
  size_t kept = 0, dropped = 0, by_one = 0;
  for (int y = 0; y < 120; ++y) {
    for (int x = 0; x < 160; ++x) {
      const int a = Inside(views[2], Reproject(views, 0, 2, x, y));
      const int b = Inside(views[1], Reproject(views, 0, 1, x, y));
      if (a < 0 || b < 0) continue;
      const bool seen_by_three = a == 1 && b == 1;
      EXPECT_EQ(std::isfinite(f[0].at(x, y)), seen_by_three) << x << "," << y;
      EXPECT_TRUE(!std::isfinite(f[0].at(x, y)) || f[0].at(x, y) == views[0].depth.at(x, y));
      EXPECT_EQ(std::isfinite(w[0].at(x, y)), a == 1 || b == 1) << x << "," << y;
      (seen_by_three ? kept : dropped)++;
      by_one += !seen_by_three && (a == 1 || b == 1);
    }
  }
  EXPECT_GT(kept, 5000u);
  EXPECT_GT(dropped, 1000u);
  EXPECT_GT(by_one, 500u);
}

TEST(Consistency, ASurfaceThatAThirdViewSeesThroughNeedsTwoConfirmations) {
  // A box 3 in front of the wall (x -1.2..-0.2, z 2.4..3.4) that views 0 and 1 saw and view 2
  // did not (it drove away). For view 0's pixels of the box's front face (hand-derived with
  // Reproject/Inside):
  //  * where view 2 sees the wall behind the box's point, view 2 could have confirmed it and did
  //    not: with views 1 and 2 both witnesses, min_agree 2 drops the pixel;
  //  * where view 2's image does not reach (x < -0.6), view 1 is the only witness: its
  //    agreement keeps the pixel;
  //  * where view 2 saw something nearer (a band of its depth map set to 1, an object right in
  //    front of it), view 2 is occluded there, not a witness: kept on view 1's word.
  // min_agree 1 keeps the box everywhere view 1 sees it.
  Scene with_box = WallScene();
  with_box.boxes.push_back({{-1.2, -0.5, 2.4}, {-0.2, 0.5, 3.4}});
  const Camera cam = MakeCamera(160, 120, 120);
  std::vector<DepthView> views;
  for (int i = 0; i < 3; ++i) {
    const Eigen::Vector3d c(0.5 * i, 0, 0);
    views.push_back(
        Render(i < 2 ? with_box : WallScene(), cam, LookAt(c, c + Eigen::Vector3d(0, 0, 1))));
  }
  constexpr int kBand0 = 8, kBand1 = 14;  // view 2's columns that saw an object at depth 1
  for (int y = 0; y < 120; ++y)
    for (int x = kBand0; x < kBand1; ++x) views[2].depth.at(x, y) = 1.0f;
  const std::vector<Image> w = FilterConsistentDepth(views, {});
  ConsistencyOptions one;
  one.min_agree = 1;
  const std::vector<Image> w1 = FilterConsistentDepth(views, one);
  const DepthView wall0 = Render(WallScene(), cam, views[0].world_to_camera);
  size_t dropped = 0, kept_alone = 0, kept_occluded = 0;
  for (int y = 1; y < 119; ++y) {
    for (int x = 1; x < 159; ++x) {
      // The box's front face, away from its edges (the side face seen at a grazing angle and
      // the corners sample across depth edges in the other views).
      bool front = true;
      for (int dy = -1; dy <= 1; ++dy)
        for (int dx = -1; dx <= 1; ++dx) {
          const float z = views[0].depth.at(x + dx, y + dy);
          front = front && z < wall0.depth.at(x + dx, y + dy) - 1.0 &&
                  std::abs(z - views[0].depth.at(x, y)) < 0.02f * z;
        }
      if (!front) continue;
      const Eigen::Vector2d p2 = Reproject(views, 0, 2, x, y);
      const int a = Inside(views[2], p2);
      const int b = Inside(views[1], Reproject(views, 0, 1, x, y));
      if (a < 0 || b != 1) continue;
      EXPECT_TRUE(std::isfinite(w1[0].at(x, y))) << x << "," << y;
      if (a == 0) {
        EXPECT_TRUE(std::isfinite(w[0].at(x, y))) << x << "," << y;
        ++kept_alone;
      } else if (p2.x() > kBand0 + 1.5 && p2.x() < kBand1 - 1.5) {
        EXPECT_TRUE(std::isfinite(w[0].at(x, y))) << x << "," << y;
        ++kept_occluded;
      } else if (p2.x() < kBand0 - 1.5 || p2.x() > kBand1 + 1.5) {
        EXPECT_FALSE(std::isfinite(w[0].at(x, y))) << x << "," << y;
        ++dropped;
      }
    }
  }
  EXPECT_GT(dropped, 300u);
  EXPECT_GT(kept_alone, 300u);
  EXPECT_GT(kept_occluded, 100u);
}

TEST(Consistency, RemovesAnOutlierPatch) {
  const Scene s = WallScene();
  std::vector<DepthView> views = WallViews(s, 4);
  for (int y = 40; y < 60; ++y) {
    for (int x = 30; x < 50; ++x) views[0].depth.at(x, y) *= 0.9f;
  }
  const std::vector<Image> f = FilterConsistentDepth(views, {});
  for (int y = 40; y < 60; ++y) {
    for (int x = 30; x < 50; ++x) EXPECT_FALSE(std::isfinite(f[0].at(x, y))) << x << "," << y;
  }
  // The clean views keep every pixel the two other clean views see, the patch's area included.
  size_t kept = 0;
  for (int y = 0; y < 120; ++y) {
    for (int x = 0; x < 160; ++x) {
      if (Inside(views[2], Reproject(views, 1, 2, x, y)) == 1 &&
          Inside(views[3], Reproject(views, 1, 3, x, y)) == 1) {
        EXPECT_TRUE(std::isfinite(f[1].at(x, y))) << x << "," << y;
        ++kept;
      }
    }
  }
  EXPECT_GT(kept, 5000u);
  // Fused, the patch leaves no surface in front of the wall.
  FusionOptions o;
  o.tsdf.voxel_per_spacing = 0.1;
  const Mesh m = FuseDepthViews(views, o);
  ASSERT_FALSE(m.vertices.empty());
  EXPECT_LT(MeshDistances(s, m, 0.05).max, kCellDiagonal);
  o.filter = false;
  EXPECT_GT(MeshDistances(s, FuseDepthViews(views, o), 0.05).max, 5.0);
}

// The box scene under x ↦ 0.2·x + (451000, 5410000, 120) fuses to the same mesh mapped alike.
// Tolerance: depth maps are float (relative rounding 6e-8 of a depth of ~100 voxels: 6e-6 voxel)
// and OpenVDB returns float vertices in index space (|index| < 300: 2e-5 voxel); world
// coordinates are double (5.4e6 · 1.1e-16 = 6e-10, 1e-7 voxel). Allowed: 1e-3 voxel.
TEST(Fusion, InvariantUnderSimilarity) {
  const double k = 0.2;
  const Eigen::Vector3d off(451000, 5410000, 120);
  const Scene a = BoxScene();
  Scene b = a;
  for (Plane& p : b.planes) p.d = k * p.d + p.n.dot(off);
  for (Box& x : b.boxes) x = {k * x.lo + off, k * x.hi + off};
  const std::vector<DepthView> va = BoxViews(a);
  std::vector<DepthView> vb;
  for (const DepthView& v : va) {
    const Eigen::Vector3d c = k * v.world_to_camera.Centre() + off;
    Rigid3d pose(v.world_to_camera.q, -(v.world_to_camera.q * c));
    vb.push_back(Render(b, v.camera, pose));
  }
  FusionOptions o;
  o.tsdf.voxel_per_spacing = 0.03;
  o.tsdf.max_depth_spacings = 5;
  const Mesh ma = FuseDepthViews(va, o), mb = FuseDepthViews(vb, o);
  const double voxel_b = 0.03 * MedianCameraSpacing(vb);
  // Camera centres at 5.4e6 carry ~1e-9 absolute error on a spacing of ~0.3.
  EXPECT_NEAR(voxel_b / (k * 0.03 * MedianCameraSpacing(va)), 1.0, 1e-8);
  ASSERT_GT(ma.vertices.size(), 1000u);
  ASSERT_EQ(ma.vertices.size(), mb.vertices.size());
  EXPECT_EQ(ma.faces, mb.faces);
  double worst = 0;
  for (size_t i = 0; i < ma.vertices.size(); ++i) {
    worst = std::max(worst, ((k * ma.vertices[i] + off) - mb.vertices[i]).norm() / voxel_b);
  }
  std::printf("  similarity: worst vertex difference %.2e voxels\n", worst);
  EXPECT_LT(worst, 1e-3);
}

TEST(Fusion, EmptyInputGivesAnEmptyMesh) {
  EXPECT_TRUE(FuseDepthViews({}, {}).vertices.empty());
  EXPECT_TRUE(FilterConsistentDepth({}, {}).empty());
  std::vector<DepthView> views = WallViews(WallScene(), 3);
  for (DepthView& v : views) {
    std::fill(v.depth.data.begin(), v.depth.data.end(), std::numeric_limits<float>::infinity());
  }
  const Mesh m = FuseDepthViews(views, {});
  EXPECT_TRUE(m.vertices.empty());
  EXPECT_TRUE(m.faces.empty());
  TsdfVolume volume(Eigen::Vector3d(451000, 5410000, 120), 0.01, 3);
  volume.Integrate(views[0]);
  EXPECT_EQ(volume.ActiveVoxels(), 0u);
  EXPECT_TRUE(volume.ExtractMesh().faces.empty());
}

TEST(Fusion, RejectsBadInputAndOptions) {
  std::vector<DepthView> views = WallViews(WallScene(), 3);
  FusionOptions o;
  o.tsdf.truncation_voxels = 0.5;
  EXPECT_THROW(FuseDepthViews(views, o), UsageError);
  o = {};
  o.consistency.relative_tolerance = 0;
  EXPECT_THROW(FuseDepthViews(views, o), UsageError);
  o = {};
  views[1].camera = views[1].camera.Scaled(80, 60);
  EXPECT_THROW(FuseDepthViews(views, o), Error);
  views = WallViews(WallScene(), 3);
  views[2].confidence = Image(10, 10, 1, 32);
  EXPECT_THROW(FilterConsistentDepth(views, {}), Error);
  // One camera: no spacing to derive a voxel from, unless it is given.
  views.resize(1);
  views[0].confidence = {};
  EXPECT_THROW(FuseDepthViews(views, {}), Error);
  o.filter = false;
  o.tsdf.voxel_size = 0.05;
  EXPECT_FALSE(FuseDepthViews(views, o).faces.empty());
}

}  // namespace mvtm
