// mesh/merge: the proxy's ground lowered and its walls moved back by hand-derived amounts.
#include "mesh/merge.h"

#include <gtest/gtest.h>

#include <cmath>
#include <vector>

#include "base/error.h"

namespace mvtm {
namespace {

// A ground quad at z = 0 (normal +z) and a wall quad at y = 5 facing −y (towards the path).
Mesh Proxy() {
  Mesh m;
  m.vertices = {{0, -1, 0}, {4, -1, 0}, {4, 1, 0}, {0, 1, 0},
                {0, 5, 0},  {4, 5, 0},  {4, 5, 3}, {0, 5, 3}};
  m.faces = {{0, 1, 2}, {0, 2, 3}, {4, 5, 6}, {4, 6, 7}};
  m.ComputeNormals();
  return m;
}

TEST(Merge, GroundLoweredWallsMovedBackDenseKept) {
  Mesh dense;
  dense.vertices = {{1, 4.9, 1}, {2, 4.9, 1}, {1, 4.9, 2}};
  dense.faces = {{0, 1, 2}};
  const Mesh proxy = Proxy();
  ASSERT_NEAR(proxy.normals[4].y(), -1, 1e-6);  // the wall faces the path
  MergeReport r;
  const Mesh m = MergeProxyBehind(dense, proxy, {0, 0, 1}, 0.25, 2.0, &r);
  EXPECT_EQ(r.ground_faces, 2u);
  EXPECT_EQ(r.wall_faces, 2u);
  ASSERT_EQ(m.faces.size(), 5u);
  EXPECT_EQ(m.faces[0], dense.faces[0]);
  ASSERT_EQ(m.vertices.size(), 3u + 8u);
  for (size_t i = 0; i < 3; ++i) EXPECT_EQ(m.vertices[i], dense.vertices[i]);
  for (uint32_t v : {3u, 4u, 5u, 6u})
    EXPECT_NEAR(m.vertices[v].z(), -0.25, 1e-12);  // ground, lowered
  for (uint32_t v : {7u, 8u, 9u, 10u})
    EXPECT_NEAR(m.vertices[v].y(), 7.0, 1e-6);  // wall, 5 + 2 back
  EXPECT_TRUE(m.has_normals());
  // Each face says what it is: the dense face measured, then the proxy's in order (its ground
  // faces at z = 0 and its wall faces at y = 5, see Proxy()).
  ASSERT_TRUE(m.has_face_kinds());
  EXPECT_EQ(m.face_kinds[0], kFaceObserved);
  for (size_t f = 1; f < m.faces.size(); ++f) {
    const bool wall = m.vertices[m.faces[f][0]].y() > 6;
    EXPECT_EQ(m.face_kinds[f], wall ? kFaceFillWall : kFaceFillGround) << f;
  }
}

TEST(Merge, AWallMovedBackTakesItsFootDownSoNoGapOpensAtTheGroundsEdge) {
  // The corridor's case: the ground reaches the wall (y = 5), whose own vertices sit on the
  // ground's edge. Moved back by 2, the wall's foot also goes 2 down: a ray from a camera 1.65
  // above the ground at y = 0 that grazes the ground's edge (2, 5, 0) goes on to y = 7 at
  // z = -1.65 · 2 / 5 = -0.66, on the wall (z from -2 to 3), not through a gap to nothing.
  Mesh proxy;
  proxy.vertices = {{0, -1, 0}, {4, -1, 0}, {4, 5, 0}, {0, 5, 0},
                    {0, 5, 0},  {4, 5, 0},  {4, 5, 3}, {0, 5, 3}};
  proxy.faces = {{0, 1, 2}, {0, 2, 3}, {4, 5, 6}, {4, 6, 7}};
  proxy.ComputeNormals();
  const Mesh m = MergeProxyBehind(Mesh(), proxy, {0, 0, 1}, 0, 2.0);
  ASSERT_EQ(m.vertices.size(), 8u);
  for (uint32_t v : {4u, 5u}) {  // the foot: back and down
    EXPECT_NEAR(m.vertices[v].y(), 7.0, 1e-6);
    EXPECT_NEAR(m.vertices[v].z(), -2.0, 1e-6);
  }
  for (uint32_t v : {6u, 7u}) {  // the top: back only
    EXPECT_NEAR(m.vertices[v].y(), 7.0, 1e-6);
    EXPECT_NEAR(m.vertices[v].z(), 3.0, 1e-6);
  }
  const double z_at_wall = 1.65 - 1.65 * 7.0 / 5.0;
  EXPECT_GT(z_at_wall, m.vertices[4].z());
  EXPECT_LT(z_at_wall, m.vertices[6].z());
  // Without walls moved back nothing moves down.
  const Mesh same = MergeProxyBehind(Mesh(), proxy, {0, 0, 1}, 0, 0);
  EXPECT_NEAR(same.vertices[4].z(), 0, 1e-12);
}

// A grid of na x nb quads of side `step` from `corner` along the unit axes `ea` and `eb` (faces
// wound to face ea x eb), scaled by `k` about the origin and moved by `o`.
Mesh Grid(const Eigen::Vector3d& corner, const Eigen::Vector3d& ea, const Eigen::Vector3d& eb,
          int na, int nb, double step, double k, const Eigen::Vector3d& o) {
  Mesh m;
  for (int j = 0; j <= nb; ++j)
    for (int i = 0; i <= na; ++i) m.vertices.push_back(k * (corner + step * (i * ea + j * eb)) + o);
  for (int j = 0; j < nb; ++j)
    for (int i = 0; i < na; ++i) {
      const uint32_t a = j * (na + 1) + i, b = a + 1, c = a + na + 1, d = c + 1;
      m.faces.push_back({a, b, d});
      m.faces.push_back({a, d, c});
    }
  return m;
}

// A flat grid of n x n quads of side `step` over [0, n·step]² in the plane z = height (up +z),
// scaled by `k` about the origin and moved by `o`.
Mesh Flat(int n, double step, double height, double k = 1, const Eigen::Vector3d& o = {0, 0, 0}) {
  return Grid({0, 0, height}, Eigen::Vector3d::UnitX(), Eigen::Vector3d::UnitY(), n, n, step, k, o);
}

// Appends `b` to `a`.
void Append(Mesh& a, const Mesh& b) {
  const uint32_t base = static_cast<uint32_t>(a.vertices.size());
  a.vertices.insert(a.vertices.end(), b.vertices.begin(), b.vertices.end());
  for (auto f : b.faces) a.faces.push_back({f[0] + base, f[1] + base, f[2] + base});
}

TEST(Merge, TheProxyGroundAboveTheFusedRoadIsMeasuredAndGoesUnderIt) {
  // The fused road at z = 0 (20 x 20 quads of 0.5) under a wider tree canopy at z = 4 (more
  // faces than the road; not the road: beyond the bound); the proxy's ground (a grid of 1.0) at z =
  // 0.1, with a wall. Every pair is 0.1 apart: the median is 0.1, by hand. Lowered by it, the
  // proxy's ground lies at the road's height. The same scene scaled by 0.2 at UTM coordinates:
  // 0.02. A proxy below the road: negative. Fewer than 50 pairs (a road of 4 quads): 0.
  for (const double k : {1.0, 0.2}) {
    const Eigen::Vector3d o =
        k == 1.0 ? Eigen::Vector3d::Zero() : Eigen::Vector3d(451000, 5410000, 120);
    Mesh dense = Flat(20, 0.5, 0.0, k, o);
    Append(dense, Flat(28, 0.35, 4.0, k, o));  // more canopy than road
    Mesh proxy = Flat(10, 1.0, 0.1, k, o);
    Append(proxy, Proxy());  // a wall (and a second ground quad at z = 0: one pair of many)
    proxy.ComputeNormals();
    const double above = ProxyGroundAbove(dense, proxy, {0, 0, 1}, 1.0 * k, 0.5 * k);
    EXPECT_NEAR(above, 0.1 * k, 1e-6 * k) << k;
    const Mesh m = MergeProxyBehind(dense, Flat(10, 1.0, 0.1, k, o), {0, 0, 1}, above, -1);
    for (size_t v = dense.vertices.size(); v < m.vertices.size(); ++v)
      EXPECT_NEAR(m.vertices[v].z(), o.z(), 1e-6) << v;
    EXPECT_NEAR(ProxyGroundAbove(dense, Flat(10, 1.0, -0.2, k, o), {0, 0, 1}, 1.0 * k, 0.5 * k),
                -0.2 * k, 1e-6 * k);
  }
  EXPECT_EQ(ProxyGroundAbove(Flat(2, 0.5, 0), Flat(10, 1.0, 0.1), {0, 0, 1}, 1.0, 0.5), 0.0);
  EXPECT_THROW(ProxyGroundAbove(Flat(2, 0.5, 0), Flat(10, 1.0, 0.1), {0, 0, 1}, 0, 0.5), Error);
}

// A vertical grid in the plane y = `y` over x in [x0, x0 + na·step], z in [0, nz·step], wound to
// face −y (towards a path at y = 0); scaled by `k` about the origin and moved by `o`.
Mesh Upright(double x0, int na, int nz, double step, double y, double k = 1,
             const Eigen::Vector3d& o = {0, 0, 0}) {
  return Grid({x0, y, 0}, Eigen::Vector3d::UnitX(), Eigen::Vector3d::UnitZ(), na, nz, step, k, o);
}

TEST(Merge, AWallGoesJustBehindAFlatFusedFacadeAndNotBehindAHedge) {
  // The proxy's wall at y = 5 (x 0..20, z 0..6, step 1). Fused: a flat facade at y = 7 (x 0..10,
  // z 0..3, step 0.25: 2 behind the wall) and a hedge of two layers at y = 5.5 and 8.5 (x 12..20,
  // z 0..6: interquartile range 3). With reach 1 along the wall, rise 0.5, spread 0.3: the wall's
  // vertices at x <= 9, z <= 3 see only facade faces, all 2 behind: offset 2 (the median), by
  // hand; at z >= 4 the facade's faces are more than 0.5 below: none; at x >= 13 the hedge's
  // spread is 3 > 0.3: none. Merged with offset + 0.5, those vertices go to y = 7.5; the rest
  // to y = 5 + 20 (walls_behind). The same scene scaled by 0.2 at UTM coordinates: 0.2 of each.
  for (const double k : {1.0, 0.2}) {
    const Eigen::Vector3d o =
        k == 1.0 ? Eigen::Vector3d::Zero() : Eigen::Vector3d(451000, 5410000, 120);
    Mesh proxy = Upright(0, 20, 6, 1.0, 5.0, k, o);
    proxy.ComputeNormals();
    ASSERT_NEAR(proxy.normals[0].y(), -1, 1e-6);
    Mesh dense = Upright(0, 40, 12, 0.25, 7.0, k, o);
    Append(dense, Upright(12, 32, 24, 0.25, 5.5, k, o));
    Append(dense, Upright(12, 32, 24, 0.25, 8.5, k, o));
    FacadeSearch fs;
    fs.reach = 1.0 * k;
    fs.rise = 0.5 * k;
    fs.front = 3 * k;
    fs.back = 30 * k;
    fs.spread = 0.3 * k;
    fs.quantile = 0.5;
    const std::vector<double> behind = DenseFacadeBehindWalls(dense, proxy, {0, 0, 1}, fs);
    ASSERT_EQ(behind.size(), proxy.vertices.size());
    size_t facade = 0, none = 0;
    auto region = [&](const Eigen::Vector3d& p) {  // 1 facade, 0 none, -1 not asserted
      const Eigen::Vector3d q = (p - o) / k;
      if (q.x() <= 9 + 1e-9 && q.z() <= 3 + 1e-9) return 1;
      if (q.x() >= 13 - 1e-9 || q.z() >= 4 - 1e-9) return 0;
      return -1;
    };
    for (size_t v = 0; v < proxy.vertices.size(); ++v) {
      const int r = region(proxy.vertices[v]);
      if (r == 1) {
        EXPECT_NEAR(behind[v], 2.0 * k, 1e-6 * k) << v;
        ++facade;
      } else if (r == 0) {
        EXPECT_TRUE(std::isnan(behind[v])) << v << " " << behind[v];
        ++none;
      }
    }
    EXPECT_EQ(facade, 40u);  // x 0..9, z 0..3
    EXPECT_GT(none, 60u);
    std::vector<double> offsets = behind;
    for (double& b : offsets) b += 0.5 * k;
    MergeReport r;
    const Mesh m = MergeProxyBehind(dense, proxy, {0, 0, 1}, 0, 20 * k, &r, offsets);
    EXPECT_EQ(r.wall_faces, proxy.faces.size());
    for (size_t v = dense.vertices.size(); v < m.vertices.size(); ++v) {
      const int reg = region(m.vertices[v]);
      const double y = (m.vertices[v].y() - o.y()) / k;
      if (reg == 1) {
        EXPECT_NEAR(y, 7.5, 1e-6) << v;
      } else if (reg == 0) {
        EXPECT_NEAR(y, 25.0, 1e-6) << v;
      }
    }
  }
  FacadeSearch bad;
  EXPECT_THROW(DenseFacadeBehindWalls(Mesh(), Proxy(), {0, 0, 1}, bad), Error);  // reach 0
  EXPECT_THROW(MergeProxyBehind(Mesh(), Proxy(), {0, 0, 1}, 0, 1, nullptr, {1.0}), Error);
}

TEST(Merge, AWallStandsWhereThePhotosSawThroughIt) {
  // The proxy: a wall at y = 5 facing the path (x 0..30, z 0..6, step 1), the ground under the
  // path (z = 0, y -5..5, x 0..30) and a second wall (x 40..50) that no sight meets. The dense
  // surface: a facade at y = 9 (x 12..22, z -2..5). Sights from cameras at y = 0, z = 1.5, 2
  // behind along x, through the wall at (xh, 5, zh) on a 0.1 grid (xh < 20, zh < 3):
  //   A  xh < 6:        the point 3 behind the wall (no dense surface: a hole);
  //   B  6 <= xh < 11:  200 behind (open country; clamped to back = 50); the rays from xh >= 10.4
  //                     meet the dense facade between the wall and their point: covered, 4;
  //   C  11 <= xh < 20: half on the dense facade (4 behind: covered), half 2 behind (a hedge
  //                     in front of it, seen through a hole of the dense surface).
  // Twice as many sights end in front of the wall (a tree: nothing) and as many go down to the
  // ground just in front of the wall's foot (nothing either). Reach 1, rise 0.5; by hand: x <= 5
  // 3 (the holes' median), 7 <= x <= 10 50 (holes 50, covered 4), 11 <= x <= 20 4 (the holes
  // say 2 (at x = 11 more 2s than 50s), the covered samples' 0.9 quantile 4: the wall does not
  // hide the facade; the B rays that meet the facade counted as holes to their point would make
  // x = 11 50); above z = 3 no sample within 0.5, a vertex takes its column's median (the same);
  // x >= 21 no sample within reach and no valued column within 0.5: the wall's median, 4 (valued
  // vertices: 24 of 3, 40 of 4 (x 11..20), 16 of 50, 4 of 3 to 50 at x = 6); the second wall and
  // the ground NaN. The same scene scaled by 0.2 at UTM coordinates: 0.2 of each; and with up
  // leaning by 1.1 degrees (a column of the wall is then not straight up: its fill must still
  // find it).
  struct Case {
    double k;
    Eigen::Vector3d o, up;
  };
  for (const Case& c :
       {Case{1.0, {0, 0, 0}, {0, 0, 1}}, Case{0.2, {451000, 5410000, 120}, {0, 0, 1}},
        Case{1.0, {0, 0, 0}, {0, 0.02, 1}}}) {
    const double k = c.k;
    const Eigen::Vector3d o = c.o;
    Mesh proxy = Upright(0, 30, 6, 1.0, 5.0, k, o);
    const size_t first_wall = proxy.vertices.size();
    Append(proxy, Upright(40, 10, 6, 1.0, 5.0, k, o));
    Append(proxy,
           Grid({0, -5, 0}, Eigen::Vector3d::UnitX(), Eigen::Vector3d::UnitY(), 30, 10, 1.0, k, o));
    const Mesh dense =
        Grid({12, 9, -2}, Eigen::Vector3d::UnitX(), Eigen::Vector3d::UnitZ(), 40, 28, 0.25, k, o);
    std::vector<Sight> sights;
    auto at = [&](const Eigen::Vector3d& p) { return Eigen::Vector3d(k * p + o); };
    for (int i = 0; i < 200; ++i)
      for (int j = 0; j < 30; ++j) {
        const double xh = 0.05 + 0.1 * i, zh = 0.05 + 0.1 * j;
        const Eigen::Vector3d cam(xh - 2, 0, 1.5), h(xh, 5, zh);
        const double d = xh < 6 ? 3 : xh < 11 ? 200 : (i + j) % 2 ? 4 : 2;
        sights.push_back({at(cam), at(cam + (h - cam) * (5 + d) / 5)});
        sights.push_back({at(cam), at(cam + (h - cam) * 0.8)});
        sights.push_back({at(cam), at(cam + (h - cam) * 0.7)});
        sights.push_back({at({xh - 2, 4, 1.5}), at({xh, 4.9, -1})});
      }
    SeenWallSearch s;
    s.reach = 1.0 * k;
    s.rise = 0.5 * k;
    s.back = 50 * k;
    const std::vector<double> seen = SeenWallDistances(proxy, c.up, sights, dense, s);
    ASSERT_EQ(seen.size(), proxy.vertices.size());
    size_t asserted = 0;
    for (size_t v = 0; v < proxy.vertices.size(); ++v) {
      const Eigen::Vector3d q = (proxy.vertices[v] - o) / k;
      double want = NAN;
      if (v >= first_wall)
        want = NAN;
      else if (q.x() <= 5 + 1e-9)
        want = 3;
      else if (q.x() >= 7 - 1e-9 && q.x() <= 10 + 1e-9)
        want = 50;
      else if (q.x() >= 11 - 1e-9)
        want = 4;
      else
        continue;
      if (std::isnan(want)) {
        EXPECT_TRUE(std::isnan(seen[v])) << v << " " << q.transpose();
      } else {
        EXPECT_NEAR(seen[v], want * k, 1e-6 * k) << v << " " << q.transpose();
      }
      ++asserted;
    }
    EXPECT_EQ(asserted, proxy.vertices.size() - 7);  // all but x = 6
  }
  SeenWallSearch bad;  // reach 0
  EXPECT_THROW(SeenWallDistances(Proxy(), {0, 0, 1}, {}, Mesh(), bad), Error);
}

TEST(Merge, NoWallsAndBadInput) {
  MergeReport r;
  const Mesh m = MergeProxyBehind(Mesh(), Proxy(), {0, 0, 2}, 0, -1, &r);
  EXPECT_EQ(r.ground_faces, 2u);
  EXPECT_EQ(r.wall_faces, 0u);
  EXPECT_EQ(m.faces.size(), 2u);
  EXPECT_EQ(m.vertices.size(), 4u);  // shared ground vertices stay shared
  EXPECT_THROW(MergeProxyBehind(Mesh(), Proxy(), {0, 0, 0}, 0, 1), Error);
  EXPECT_THROW(MergeProxyBehind(Mesh(), Proxy(), {0, 0, 1}, -1, 1), Error);
  Mesh bare = Proxy();
  bare.normals.clear();
  EXPECT_THROW(MergeProxyBehind(Mesh(), bare, {0, 0, 1}, 0, 1), Error);
}

}  // namespace
}  // namespace mvtm
