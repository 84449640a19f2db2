// libcore/mesh vertex colours against values worked out by hand: constant images give their
// colour; two cameras above a plane mix by cos/distance = h / (r² + h²); a plane hides the one
// below it; a camera behind the surface colours nothing; an image smaller than its camera is
// sampled through the scaled camera; 16-bit grey is brought to 8 bits.
#include "mesh/vertex_colours.h"

#include <gtest/gtest.h>

#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <memory>

#include "base/error.h"
#include "render/context.h"

namespace mvtm {
namespace {

// A GL context current for each test (the baker renders depth maps).
class VertexColours : public ::testing::Test {
 protected:
  std::unique_ptr<GlContext> ctx_ = GlContext::Create();
};

// PINHOLE 200×200, f = 50, principal point at the centre: ±4 visible at distance 2.
Camera Cam() {
  Camera c;
  c.model = CameraModel::kPinhole;
  c.width = c.height = 200;
  c.params = {50, 50, 100, 100};
  return c;
}

// A camera at (0, 0, h) looking straight down (−z), image x along world x.
Rigid3d Down(double h) {
  Eigen::Matrix3d w2c;
  w2c << 1, 0, 0, 0, -1, 0, 0, 0, -1;
  const Eigen::Quaterniond q(w2c);
  return Rigid3d(q, -(q * Eigen::Vector3d(0, 0, h)));
}

// Appends the square [−s, s]² at height z as n×n quads facing up.
void AddPlane(Mesh& m, double s, double z, int n) {
  const uint32_t base = uint32_t(m.vertices.size()), row = uint32_t(n + 1);
  for (int j = 0; j <= n; ++j)
    for (int i = 0; i <= n; ++i)
      m.vertices.push_back(Eigen::Vector3d(-s + 2 * s * i / n, -s + 2 * s * j / n, z));
  for (uint32_t j = 0; j < uint32_t(n); ++j)
    for (uint32_t i = 0; i < uint32_t(n); ++i) {
      const uint32_t a = base + j * row + i;
      m.faces.push_back({a, a + 1, a + row + 1});
      m.faces.push_back({a, a + row + 1, a + row});
    }
}

Mesh Plane() {  // [−2, 2]² at z = 0, vertices 0.25 apart
  Mesh m;
  AddPlane(m, 2, 0, 16);
  m.ComputeNormals();
  return m;
}

Image Constant(int w, int h, std::array<float, 3> rgb) {
  Image im(w, h, 3, 8);
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x)
      for (int c = 0; c < 3; ++c) im.at(x, y, c) = rgb[size_t(c)];
  return im;
}

using Rgb = std::array<uint8_t, 3>;

TEST_F(VertexColours, ConstantImageGivesItsColourEverywhereSeen) {
  Mesh m = Plane();
  VertexColourBaker baker(m);
  baker.Add(Cam(), Down(2), Constant(200, 200, {200, 100, 50}));
  EXPECT_EQ(baker.Finish(m), m.vertices.size());
  ASSERT_TRUE(m.has_colors());
  for (const Rgb& c : m.colors) EXPECT_EQ(c, (Rgb{200, 100, 50}));
}

TEST_F(VertexColours, TwoImagesMixByCosineOverDistance) {
  Mesh m = Plane();
  VertexColourBaker baker(m);
  const std::array<float, 3> a = {90, 30, 0}, b = {180, 240, 255};
  baker.Add(Cam(), Down(2), Constant(200, 200, a));
  baker.Add(Cam(), Down(4), Constant(200, 200, b));
  EXPECT_EQ(baker.Finish(m), m.vertices.size());
  for (size_t v = 0; v < m.vertices.size(); ++v) {
    // cos = h / dist, so the weight cos / dist is h / dist² = h / (r² + h²).
    const double r2 = m.vertices[v].head<2>().squaredNorm();
    const double wa = 2 / (r2 + 4), wb = 4 / (r2 + 16);
    for (size_t c = 0; c < 3; ++c)
      EXPECT_NEAR(m.colors[v][c], (wa * a[c] + wb * b[c]) / (wa + wb), 0.5 + 1e-6) << v << " " << c;
  }
  // Below the cameras: weights 1/2 and 1/4, i.e. (2a + b) / 3 = (120, 100, 85).
  EXPECT_EQ(m.colors[8 * 17 + 8], (Rgb{120, 100, 85}));
}

TEST_F(VertexColours, HiddenVerticesTakeTheirSeenNeighboursColour) {
  Mesh m;
  AddPlane(m, 2, 0, 16);  // vertices 0..288
  AddPlane(m, 1, 1, 8);   // above its centre: hides |x|, |y| < 1 from a camera straight above
  m.ComputeNormals();
  VertexColourBaker baker(m);
  baker.Add(Cam(), Down(3), Constant(200, 200, {10, 20, 30}));
  baker.Finish(m);
  size_t hidden = 0, seen = 0;
  for (size_t v = 0; v < m.vertices.size(); ++v) {
    const double extent = m.vertices[v].head<2>().cwiseAbs().maxCoeff();
    if (v >= 17 * 17 || extent >= 1.75) {  // the upper plane, or well outside its shadow
      EXPECT_EQ(m.colors[v], (Rgb{10, 20, 30})) << v;
      ++seen;
    } else if (extent <= 0.75) {  // 12.5 px or more inside the upper plane's 25 px
      // Unseen, and reached from the seen part of its plane: the seen colour, never grey.
      EXPECT_EQ(m.colors[v], (Rgb{10, 20, 30})) << v;
      ++hidden;
    }
  }
  EXPECT_EQ(hidden, 7u * 7u);
  EXPECT_EQ(seen, 9u * 9u + (17u * 17u - 13u * 13u));
}

TEST_F(VertexColours, SurfaceFacingAwayIsNotColoured) {
  Mesh m = Plane();
  VertexColourBaker baker(m);
  // Below the plane looking up (identity rotation: camera z = world z).
  baker.Add(Cam(), Rigid3d(Eigen::Quaterniond::Identity(), Eigen::Vector3d(0, 0, 2)),
            Constant(200, 200, {255, 255, 255}));
  EXPECT_EQ(baker.Finish(m), 0u);
  for (const Rgb& c : m.colors) EXPECT_EQ(c, (Rgb{128, 128, 128}));
}

TEST_F(VertexColours, SmallerImageIsSampledThroughTheScaledCamera) {
  Mesh m = Plane();
  Image im = Constant(100, 100, {255, 0, 0});  // left half red, right half blue
  for (int y = 0; y < 100; ++y)
    for (int x = 50; x < 100; ++x) im.at(x, y, 0) = 0, im.at(x, y, 2) = 255;
  VertexColourBaker baker(m);
  baker.Add(Cam(), Down(2), im);
  baker.Finish(m);
  // World x maps to column 50 + 12.5 x of the 100-wide image (column 100 + 25 x unscaled).
  for (size_t v = 0; v < m.vertices.size(); ++v) {
    const double x = m.vertices[v].x();
    if (x <= -0.25) {
      EXPECT_EQ(m.colors[v], (Rgb{255, 0, 0})) << v;
    } else if (x >= 0.25) {
      EXPECT_EQ(m.colors[v], (Rgb{0, 0, 255})) << v;
    }
  }
}

TEST_F(VertexColours, SixteenBitGreyBecomesEightBitGrey) {
  Mesh m = Plane();
  Image grey(200, 200, 1, 16, 26214.f);  // 26214 / 257 = 102
  VertexColourBaker baker(m);
  baker.Add(Cam(), Down(2), grey);
  baker.Finish(m);
  for (const Rgb& c : m.colors) EXPECT_EQ(c, (Rgb{102, 102, 102}));
}

TEST_F(VertexColours, BadInputsThrow) {
  Mesh m = Plane();
  Mesh no_normals = m;
  no_normals.normals.clear();
  EXPECT_THROW(VertexColourBaker{no_normals}, Error);
  VertexColourBaker baker(m);
  Camera radial = Cam();
  radial.model = CameraModel::kSimpleRadial;
  radial.params = {50, 100, 100, 0.1};
  EXPECT_THROW(baker.Add(radial, Down(2), Constant(200, 200, {1, 2, 3})), Error);
  Mesh other;
  AddPlane(other, 1, 0, 2);
  EXPECT_THROW(baker.Finish(other), Error);
}

}  // namespace
}  // namespace mvtm
