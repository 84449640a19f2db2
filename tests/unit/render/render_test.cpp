// libcore/render against analytic truth on hand-built meshes: planes at known depths, exact
// self-projection, and the hard cases of projective texturing (points on and behind the
// projector plane, grazing triangles, a projector that sees nothing, bad inputs).
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <functional>
#include <limits>

#include "base/error.h"
#include "gl_suite.h"
#include "render/context.h"
#include "render/gl_program.h"
#include "render/renderer.h"

namespace mvtm {
namespace {

class RenderTest : public GlSuite {};

Camera Cam(int w = 64, int h = 48, double f = 50) {
  return ParseCameraSpec("PINHOLE " + std::to_string(w) + " " + std::to_string(h) + " " +
                         std::to_string(f) + " " + std::to_string(f) + " " +
                         std::to_string(w / 2.0) + " " + std::to_string(h / 2.0));
}

// A grid of nx×ny quads (two triangles each) over vertices at(i, j), coloured rgb(i, j).
Mesh Grid(int nx, int ny, const std::function<Eigen::Vector3d(int, int)>& at,
          const std::function<std::array<uint8_t, 3>(int, int)>& rgb) {
  Mesh m;
  for (int j = 0; j <= ny; ++j)
    for (int i = 0; i <= nx; ++i) {
      m.vertices.push_back(at(i, j));
      m.colors.push_back(rgb(i, j));
    }
  for (int j = 0; j < ny; ++j)
    for (int i = 0; i < nx; ++i) {
      uint32_t a = j * (nx + 1) + i, b = a + 1, c = a + nx + 1, d = c + 1;
      m.faces.push_back({a, b, d});
      m.faces.push_back({a, d, c});
    }
  return m;
}

// A square [−s, s]² in the plane z = depth of world coordinates, offset by `o`, as a grid of
// n×n quads with vertex colour (r, g, b).
Mesh Plane(double s, double depth, const Eigen::Vector3d& o = Eigen::Vector3d::Zero(), int n = 4,
           std::array<uint8_t, 3> rgb = {10, 200, 30}) {
  return Grid(
      n, n,
      [&](int i, int j) {
        return Eigen::Vector3d(o + Eigen::Vector3d(-s + 2 * s * i / n, -s + 2 * s * j / n, depth));
      },
      [&](int, int) { return rgb; });
}

// A test pattern with a distinct value per pixel (colour), so a wrong texel shows.
Image Pattern(int w, int h) {
  Image im(w, h, 3, 8);
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x) {
      im.at(x, y, 0) = float((x * 37 + y * 11) % 256);
      im.at(x, y, 1) = float((y * 53 + x * 3) % 256);
      im.at(x, y, 2) = float((x * y) % 256);
    }
  return im;
}

// A camera at `c` looking at `target`, image "down" as close to world +y as possible.
Rigid3d LookAt(const Eigen::Vector3d& c, const Eigen::Vector3d& target) {
  Eigen::Vector3d z = (target - c).normalized();
  Eigen::Vector3d x = Eigen::Vector3d::UnitY().cross(z).normalized();
  Eigen::Vector3d y = z.cross(x);
  Eigen::Matrix3d R;  // world → camera: rows are the camera axes
  R.row(0) = x;
  R.row(1) = y;
  R.row(2) = z;
  return Rigid3d(Eigen::Quaterniond(R), -(R * c));
}

Rigid3d LookingDownZ(const Eigen::Vector3d& centre) {  // identity rotation: camera z = world z
  return Rigid3d(Eigen::Quaterniond::Identity(), -centre);
}

TEST_F(RenderTest, DepthOfAPlaneIsItsDistance) {
  Renderer r(Plane(5, 10));
  View v{Cam(), LookingDownZ({0, 0, 0})};
  Image d = r.RenderDepth(v);
  // The plane spans ±5 m at 10 m: pixels with |x−cx| < 25 px see it, the rest see nothing.
  EXPECT_NEAR(d.at(32, 24), 10.0, 1e-5);
  EXPECT_NEAR(d.at(10, 5), 10.0, 1e-5);
  EXPECT_TRUE(std::isinf(d.at(0, 0)));
  EXPECT_TRUE(std::isinf(d.at(63, 47)));
}

TEST_F(RenderTest, UtmCoordinatesRenderLikeTheOrigin) {
  const Eigen::Vector3d utm(451000.25, 5410000.75, 120.5);
  Renderer local(Plane(5, 10, Eigen::Vector3d::Zero(), 8));
  Renderer far(Plane(5, 10, utm, 8));
  // A slanted view so depth varies across the image.
  Rigid3d pose(Eigen::Quaterniond(Eigen::AngleAxisd(0.3, Eigen::Vector3d::UnitY())),
               Eigen::Vector3d::Zero());
  Rigid3d at_local = pose * LookingDownZ({1, -0.5, 0});
  Rigid3d at_far = pose * LookingDownZ(Eigen::Vector3d(1, -0.5, 0) + utm);
  Image a = local.RenderDepth({Cam(), at_local}), b = far.RenderDepth({Cam(), at_far});
  double worst = 0;
  for (size_t i = 0; i < a.data.size(); ++i) {
    ASSERT_EQ(std::isinf(a.data[i]), std::isinf(b.data[i])) << i;
    if (!std::isinf(a.data[i]))
      worst = std::max(worst, std::abs(a.data[i] - b.data[i]) / double(a.data[i]));
  }
  EXPECT_LT(worst, 1e-6);  // a float32 mesh at UTM without re-centring would be off by decimetres
}

TEST_F(RenderTest, SelfProjectionReproducesTheImage) {
  // Rendering a projector's own pose with its own image gives the image back exactly: pixel
  // centres project onto texel centres, where bilinear sampling returns the texel.
  Renderer r(Plane(50, 10, Eigen::Vector3d::Zero(), 8));
  Camera c = Cam();
  Image img = Pattern(64, 48);
  View v{c, LookingDownZ({0.3, 0.2, 0})};
  Projector p{v, &img, nullptr, nullptr};
  EffectsPlan plan;
  Renderer::Frame f = r.Render(v, {p}, plan);
  EXPECT_EQ(f.colour.data, img.data);
  for (float s : f.source.data) ASSERT_EQ(s, 0.f);
}

TEST_F(RenderTest, ExposureBringsProjectorsToTheCommonFrame) {
  // A projector recorded at gain 2 and offset 10 (I = 2L + 10): with the exposure effect its
  // own pose renders L = (I - 10) / 2, rounded to 8 bits (within half a grey level: the shader
  // computes in float on the 0..1 scale). Without the effect the image comes back unchanged.
  Renderer r(Plane(50, 10, Eigen::Vector3d::Zero(), 8));
  Image img = Pattern(64, 48);
  View v{Cam(), LookingDownZ({0.3, 0.2, 0})};
  Projector p{v, &img, nullptr, nullptr};
  p.exposure = CameraExposure{2.f, 10.f};
  EffectsPlan plan;
  plan.exposure = true;
  const Renderer::Frame f = r.Render(v, {p}, plan);
  for (size_t i = 0; i < img.data.size(); ++i) {
    const float want = std::max(0.f, (img.data[i] - 10.f) / 2.f);
    ASSERT_NEAR(f.colour.data[i], want, 0.5f + 1e-3f) << i;
  }
  plan.exposure = false;
  EXPECT_EQ(r.Render(v, {p}, plan).colour.data, img.data);
}

TEST_F(RenderTest, GeometryBehindTheProjectorIsNotTextured) {
  // The render camera at z = 0 looks at a plane at z = 10 (+z); the projector at z = 20 looks
  // along +z too, so the plane is *behind* it (z_proj = −10).
  // Without reverse-projection rejection the image would appear mirrored on the plane.
  Renderer r(Plane(50, 10, Eigen::Vector3d::Zero(), 8));
  Image img = Pattern(64, 48);
  Projector p{View{Cam(), LookingDownZ({0, 0, 20})}, &img, nullptr, nullptr};
  Renderer::Frame f = r.Render(View{Cam(), LookingDownZ({0, 0, 0})}, {p}, EffectsPlan());
  for (size_t i = 0; i < f.source.data.size(); ++i) {
    ASSERT_EQ(f.source.data[i], kSourceVertex) << i;
    ASSERT_EQ(f.colour.data[i * 3 + 1], 200.f);  // the vertex colour (10, 200, 30)
  }
}

TEST_F(RenderTest, VertexExactlyOnTheProjectorPlane) {
  // A plane z ∈ [−10, 10] seen from the side: it crosses the projector plane z = 0, with grid
  // vertices exactly on it (w = 0). Pixels whose point is in front of the projector take its
  // texture; those on or behind the plane fall back; nothing is NaN or mirrored.
  Mesh m;
  int n = 10;
  for (int j = 0; j <= n; ++j)
    for (int i = 0; i <= n; ++i) {
      m.vertices.push_back(
          Eigen::Vector3d(-10 + 20.0 * i / n, 3, -10 + 20.0 * j / n));  // y = 3: a floor
      m.colors.push_back({1, 2, 3});
    }
  for (int j = 0; j < n; ++j)
    for (int i = 0; i < n; ++i) {
      uint32_t a = j * (n + 1) + i, b = a + 1, c = a + n + 1, d = c + 1;
      m.faces.push_back({a, b, d});
      m.faces.push_back({a, d, c});
    }
  Renderer r(m);
  Image img = Pattern(64, 48);
  View proj{Cam(64, 48, 20), LookingDownZ({0, 0, 0})};
  // The render camera above and behind, looking down at the floor across the projector plane.
  View view{Cam(64, 48, 30), LookAt({0, -2, -12}, {0, 3, 2})};
  Image depth = r.RenderDepth(view);
  Renderer::Frame f = r.Render(view, {Projector{proj, &img, nullptr, nullptr}}, EffectsPlan());
  size_t textured = 0, fallback = 0;
  for (int y = 0; y < 48; ++y)
    for (int x = 0; x < 64; ++x) {
      float z = depth.at(x, y);
      if (std::isinf(z)) continue;
      // The surface point of this pixel, independently, in double.
      Eigen::Vector3d X =
          view.world_to_camera.Inverse() * view.camera.Unproject({x + 0.5, y + 0.5}, z);
      Eigen::Vector3d xp = proj.world_to_camera * X;
      uint8_t src = static_cast<uint8_t>(f.source.at(x, y));
      for (int c = 0; c < 3; ++c) ASSERT_TRUE(std::isfinite(f.colour.at(x, y, c)));
      if (src == 0) {
        ++textured;
        EXPECT_GT(xp.z(), -1e-3) << x << "," << y;  // never from behind the plane
      } else {
        ++fallback;
        EXPECT_EQ(src, kSourceVertex);
        Eigen::Vector2d uv = proj.camera.Project(xp);
        bool inside = xp.z() > 0.05 && uv.x() > 1 && uv.y() > 1 && uv.x() < 63 && uv.y() < 47;
        EXPECT_FALSE(inside) << "fell back although the projector sees " << x << "," << y;
      }
    }
  EXPECT_GT(textured, 50u);
  EXPECT_GT(fallback, 50u);
}

TEST_F(RenderTest, GrazingTrianglesStayFiniteAndCorrect) {
  // A plane almost parallel to the projector's rays (89.5° from its normal).
  Mesh m = Plane(20, 0, Eigen::Vector3d::Zero(), 16);
  Eigen::Matrix3d tilt =
      Eigen::AngleAxisd(M_PI / 2 - 0.5 * M_PI / 180, Eigen::Vector3d::UnitX()).toRotationMatrix();
  for (auto& v : m.vertices) v = tilt * v + Eigen::Vector3d(0, 0, 30);
  Renderer r(m);
  Image img = Pattern(64, 48);
  View proj{Cam(), LookingDownZ({0, 0, 0})};
  View view{Cam(), LookAt({0, -8, 10}, {0, 0, 30})};
  Image depth = r.RenderDepth(view);
  Renderer::Frame f = r.Render(view, {Projector{proj, &img, nullptr, nullptr}}, EffectsPlan());
  size_t checked = 0;
  for (int y = 0; y < 48; ++y)
    for (int x = 0; x < 64; ++x) {
      if (std::isinf(depth.at(x, y)) || f.source.at(x, y) != 0) continue;
      Eigen::Vector3d X = view.world_to_camera.Inverse() *
                          view.camera.Unproject({x + 0.5, y + 0.5}, depth.at(x, y));
      Eigen::Vector2d uv = proj.camera.Project(proj.world_to_camera * X);
      // Where the texture lookup is well inside the image the colour is within the range of the
      // 2×2 texels around it (bilinear), however thin the triangle is in the projector.
      if (uv.x() < 2 || uv.y() < 2 || uv.x() > 62 || uv.y() > 46) continue;
      int u0 = int(std::floor(uv.x() - 0.5)), v0 = int(std::floor(uv.y() - 0.5));
      for (int c = 0; c < 3; ++c) {
        float lo = 255, hi = 0;
        for (int dy = -1; dy <= 2; ++dy)
          for (int dx = -1; dx <= 2; ++dx) {
            float t = img.at(std::clamp(u0 + dx, 0, 63), std::clamp(v0 + dy, 0, 47), c);
            lo = std::min(lo, t), hi = std::max(hi, t);
          }
        EXPECT_GE(f.colour.at(x, y, c), lo - 1) << x << "," << y;
        EXPECT_LE(f.colour.at(x, y, c), hi + 1) << x << "," << y;
      }
      ++checked;
    }
  EXPECT_GT(checked, 20u);
}

TEST_F(RenderTest, ProjectorThatSeesNoGeometry) {
  // The projector looks away from the mesh: its depth map is all +inf and it colours nothing.
  Renderer r(Plane(50, 10));
  Image img = Pattern(64, 48);
  View away{Cam(), Rigid3d(Eigen::Quaterniond(Eigen::AngleAxisd(M_PI, Eigen::Vector3d::UnitY())),
                           Eigen::Vector3d::Zero())};
  Image d = r.RenderDepth(away);
  for (float z : d.data) ASSERT_TRUE(std::isinf(z));
  EffectsPlan plan;
  plan.occlusion = true;
  plan.skybox = true;
  Renderer::Frame f =
      r.Render(View{Cam(), LookingDownZ({0, 0, 0})}, {Projector{away, &img, &d, nullptr}}, plan);
  for (float s : f.source.data) ASSERT_EQ(s, kSourceVertex);
}

TEST_F(RenderTest, SkyAtADistanceKeepsTheParallaxOfFarScenery) {
  // Nothing in view (the mesh is behind both cameras): every pixel is sky, from a projector whose
  // image is a ramp (red 10 + 2·u, green 20 + 3·v at pixel coordinates u, v: bilinear sampling
  // of it is exact). The render camera is 1 to the projector's right. With the sky at distance D
  // a render pixel's ray meets it at X = C + D·ray/|ray|, which the projector sees at K·X/X.z
  // (hand-derived: the colour is the ramp there); at infinity (0) the ray's direction alone, the
  // same pixel. At D = 20 the two differ by f·b/D = 2.5 pixels, 5 grey levels. The same scene
  // scaled by 0.2 at UTM coordinates (D scaled with it) renders the same.
  for (const double scale : {1.0, 0.2}) {
    const Eigen::Vector3d o =
        scale == 1.0 ? Eigen::Vector3d::Zero() : Eigen::Vector3d(451000, 5410000, 120);
    Renderer r(Plane(50 * scale, -10 * scale, o));
    Image ramp(64, 48, 3, 8);
    for (int y = 0; y < 48; ++y)
      for (int x = 0; x < 64; ++x) {
        ramp.at(x, y, 0) = float(10 + 2 * (x + 0.5));
        ramp.at(x, y, 1) = float(20 + 3 * (y + 0.5));
        ramp.at(x, y, 2) = 0;
      }
    const View proj{Cam(), LookingDownZ(o)};
    Image d = r.RenderDepth(proj);
    for (float z : d.data) ASSERT_TRUE(std::isinf(z));
    const View view{Cam(), LookingDownZ(o + Eigen::Vector3d(scale, 0, 0))};
    EffectsPlan plan;
    plan.occlusion = plan.skybox = true;
    for (const double D : {20.0, 0.0}) {
      plan.sky_distance = D * scale;
      Renderer::Frame f = r.Render(view, {Projector{proj, &ramp, &d, nullptr}}, plan);
      size_t checked = 0;
      for (int y = 2; y < 46; y += 3)
        for (int x = 2; x < 62; x += 3) {
          const Eigen::Vector3d ray = view.camera.Unproject({x + 0.5, y + 0.5}, 1.0);
          Eigen::Vector2d uv(x + 0.5, y + 0.5);
          if (D > 0) uv = proj.camera.Project(Eigen::Vector3d(1, 0, 0) + D * ray.normalized());
          if (uv.x() < 1 || uv.x() > 63 || uv.y() < 1 || uv.y() > 47) continue;
          ASSERT_EQ(f.source.at(x, y), 0.f) << x << "," << y;
          EXPECT_NEAR(f.colour.at(x, y, 0), 10 + 2 * uv.x(), 1.0) << D << " " << x << "," << y;
          EXPECT_NEAR(f.colour.at(x, y, 1), 20 + 3 * uv.y(), 1.0) << D << " " << x << "," << y;
          ++checked;
        }
      EXPECT_GT(checked, 250u);
      const double shift = D > 0 ? 5.0 : 0.0;  // 2 grey levels per pixel of parallax
      EXPECT_NEAR(f.colour.at(32, 24, 0) - (10 + 2 * 32.5), shift, 1.0);
    }
  }
}

TEST_F(RenderTest, OcclusionUsesTheProjectorsDepth) {
  // A small occluder (z = 5) between the projector and a wall (z = 10): the wall pixels behind
  // the occluder, seen from a side camera, must not take the occluder's texture.
  Mesh wall = Plane(50, 10, Eigen::Vector3d::Zero(), 8, {0, 0, 0});
  Mesh box = Plane(1, 5, Eigen::Vector3d::Zero(), 1, {0, 0, 0});
  uint32_t base = static_cast<uint32_t>(wall.vertices.size());
  for (size_t i = 0; i < box.vertices.size(); ++i) {
    wall.vertices.push_back(box.vertices[i]);
    wall.colors.push_back(box.colors[i]);
  }
  for (auto f : box.faces) wall.faces.push_back({f[0] + base, f[1] + base, f[2] + base});
  Renderer r(wall);
  Image img = Pattern(64, 48);
  View proj{Cam(), LookingDownZ({0, 0, 0})};
  Image pd = r.RenderDepth(proj);
  View side{Cam(), LookingDownZ({3, 0, 0})};
  EffectsPlan with;
  with.occlusion = true;
  EffectsPlan without;
  Renderer::Frame a = r.Render(side, {Projector{proj, &img, &pd, nullptr}}, with);
  Renderer::Frame b = r.Render(side, {Projector{proj, &img, nullptr, nullptr}}, without);
  Image sd = r.RenderDepth(side);
  size_t shadowed = 0;
  for (int y = 0; y < 48; ++y)
    for (int x = 0; x < 64; ++x) {
      float z = sd.at(x, y);
      if (std::isinf(z)) continue;
      Eigen::Vector3d X =
          side.world_to_camera.Inverse() * side.camera.Unproject({x + 0.5, y + 0.5}, z);
      bool on_wall = X.z() > 9;
      bool hidden = on_wall && std::abs(X.x() * 5 / 10) < 0.95 && std::abs(X.y() * 5 / 10) < 0.95;
      if (!hidden) continue;
      ++shadowed;
      EXPECT_EQ(a.source.at(x, y), kSourceVertex) << x << "," << y;  // occluded: fallback
      EXPECT_EQ(b.source.at(x, y), 0.f);                             // no test: wrongly textured
    }
  EXPECT_GT(shadowed, 10u);
}

TEST_F(RenderTest, UnneededEffectsChangeNoPixel) {
  // The plan turns effects off when the scene does not call for them; forcing them on must give
  // the same pixels: a plane filling the view (no holes: skybox unneeded), empty masks, and a
  // first projector that covers every pixel (more projectors unneeded).
  Renderer r(Plane(200, 10, Eigen::Vector3d::Zero(), 8));
  Image img = Pattern(64, 48), img2 = Pattern(64, 48);
  for (float& v : img2.data) v = 255 - v;
  Image empty_mask(64, 48, 1, 8, 0.f);
  View proj{Cam(64, 48, 40), LookingDownZ({0.2, 0.1, -1})};  // wider view, behind: covers all
  View proj2{Cam(), LookingDownZ({1, 0, 0})};
  View view{Cam(), LookingDownZ({0, 0, 0})};
  Image d1 = r.RenderDepth(proj), d2 = r.RenderDepth(proj2);
  std::vector<Projector> ps = {{proj, &img, &d1, &empty_mask}, {proj2, &img2, &d2, &empty_mask}};
  EffectsPlan base;
  base.occlusion = true;
  Renderer::Frame ref = r.Render(view, ps, base);
  for (float s : ref.source.data) ASSERT_EQ(s, 0.f);  // the first projector covers everything
  EffectsPlan sky = base, masks = base, several = base;
  sky.skybox = true;
  masks.masks = true;
  several.projectors = 2;
  EXPECT_EQ(r.Render(view, ps, sky).colour.data, ref.colour.data);
  EXPECT_EQ(r.Render(view, ps, masks).colour.data, ref.colour.data);
  EXPECT_EQ(r.Render(view, ps, several).colour.data, ref.colour.data);
  // And a needed effect does change pixels: a mask on the first projector hands them over.
  Image half = empty_mask;
  for (int y = 0; y < 48; ++y)
    for (int x = 0; x < 32; ++x) half.at(x, y) = 255;
  std::vector<Projector> masked = {{proj, &img, &d1, &half}, {proj2, &img2, &d2, &empty_mask}};
  masks.projectors = 2;
  EXPECT_NE(r.Render(view, masked, masks).colour.data, ref.colour.data);
}

TEST_F(RenderTest, BlendWeighsProjectorsByTheAngleOfTheirRays) {
  // Two flat projectors (grey 50 at x = −1, grey 200 at x = +1) facing a wall 10 away. Rendered
  // from projector A's own pose, A's rays are the render's (angle 0): A alone. Rendered from the
  // midpoint, every pixel is the documented weighted mean (EffectsPlan: weight
  // (1 / (angle + res_weight · max(0, 1 − d_render / d_proj) + 1e-3))^p), computed here in double
  // from the wall point: 125 straight ahead by symmetry. The first-projector rule paints A's 50
  // everywhere it reaches.
  Renderer r(Plane(100, 10, Eigen::Vector3d::Zero(), 8));
  Image a(64, 48, 3, 8, 50.f), b(64, 48, 3, 8, 200.f);
  const Eigen::Vector3d ca(-1, 0, 0), cb(1, 0, 0);
  View pa{Cam(), LookingDownZ(ca)}, pb{Cam(), LookingDownZ(cb)};
  Image da = r.RenderDepth(pa), db = r.RenderDepth(pb);
  std::vector<Projector> ps = {{pa, &a, &da, nullptr}, {pb, &b, &db, nullptr}};
  EffectsPlan plan;
  plan.projectors = 2;
  plan.occlusion = true;
  plan.blend = true;
  plan.weights.feather = 0;
  Renderer::Frame self = r.Render(pa, ps, plan);
  for (int x = 8; x < 56; ++x) EXPECT_NEAR(self.colour.at(x, 24, 0), 50.f, 1.f) << x;
  const View mid_view{Cam(), LookingDownZ({0, 0, 0})};
  Renderer::Frame mid = r.Render(mid_view, ps, plan);
  auto weight = [&](const Eigen::Vector3d& X, const Eigen::Vector3d& c) {
    const Eigen::Vector3d ray = X, proj = X - c;  // render camera at the origin
    const double angle = std::acos(std::clamp(ray.normalized().dot(proj.normalized()), -1., 1.));
    const double pen =
        angle + plan.weights.res_weight * std::max(0.0, 1 - ray.norm() / proj.norm());
    return std::pow(1 / (pen + 1e-3), plan.weights.power);
  };
  // +1: inside the image by half a pixel or more, −1: outside by as much, 0: on the edge.
  auto sees = [](const View& p, const Eigen::Vector3d& X) {
    const Eigen::Vector2d uv = p.camera.Project(p.world_to_camera * X);
    const double margin = std::min({uv.x(), uv.y(), 64 - uv.x(), 48 - uv.y()});
    return margin > 0.5 ? 1 : margin < -0.5 ? -1 : 0;
  };
  size_t both = 0;
  for (int y : {4, 24, 43})
    for (int x = 0; x < 64; ++x) {
      const Eigen::Vector3d X = mid_view.camera.Unproject({x + 0.5, y + 0.5}, 10.0);
      const int sa = sees(pa, X), sb = sees(pb, X);
      if (sa * sb == -1) {
        EXPECT_EQ(mid.colour.at(x, y, 0), sa > 0 ? 50.f : 200.f) << x << "," << y;
      }
      if (sa < 1 || sb < 1) continue;
      const double wa = weight(X, ca), wb = weight(X, cb);
      EXPECT_NEAR(mid.colour.at(x, y, 0), (50 * wa + 200 * wb) / (wa + wb), 1.0) << x << "," << y;
      ++both;
    }
  EXPECT_GT(both, 150u);
  EXPECT_NEAR((mid.colour.at(31, 24, 0) + mid.colour.at(32, 24, 0)) / 2, 125.f, 1.5f);
  plan.blend = false;
  Renderer::Frame first = r.Render(mid_view, ps, plan);
  for (int x = 0; x < 64; ++x)
    EXPECT_TRUE(first.source.at(x, 24) != 0.f || first.colour.at(x, 24, 0) == 50.f) << x;
}

TEST_F(RenderTest, FillLeavesNoPixelAtTheBackground) {
  // A wall with a square hole: the hole sees nothing and, without sky, is background. With the
  // fill its pixels take the colour around them (the projector's flat 80) and are marked filled.
  Mesh wall = Plane(20, 10, Eigen::Vector3d::Zero(), 10);
  std::vector<std::array<uint32_t, 3>> kept;
  for (const auto& f : wall.faces) {
    Eigen::Vector3d c = (wall.vertices[f[0]] + wall.vertices[f[1]] + wall.vertices[f[2]]) / 3;
    if (std::abs(c.x()) > 4 || std::abs(c.y()) > 4) kept.push_back(f);
  }
  wall.faces = kept;
  Renderer r(wall);
  Image img(64, 48, 3, 8, 80.f);
  View view{Cam(), LookingDownZ({0, 0, 0})};
  std::vector<Projector> ps = {{view, &img, nullptr, nullptr}};
  EffectsPlan plan;
  Renderer::Frame without = r.Render(view, ps, plan);
  size_t holes = 0;
  for (float v : without.source.data) holes += v == kSourceBackground;
  ASSERT_GT(holes, 100u);  // the scene does exercise the fill
  plan.fill = true;
  RenderStats stats;
  Renderer::Frame with = r.Render(view, ps, plan, &stats);
  size_t filled = 0;
  for (size_t p = 0; p < with.source.pixels(); ++p) {
    ASSERT_NE(with.source.data[p], kSourceBackground) << p;
    filled += with.source.data[p] == kSourceFilled;
    for (int c = 0; c < 3; ++c) ASSERT_EQ(with.colour.data[p * 3 + c], 80.f) << p;
  }
  EXPECT_EQ(filled, holes);
  EXPECT_GE(stats.fill_ms, 0.0);
}

// A ground y = 1.5 + bump(x, z) below a camera at the origin looking down +z (y down): x in
// [-60, 60], z in [0, 120], quads of 0.5 m (115k triangles).
Mesh Ground(double bump) {
  return Grid(
      240, 240,
      [bump](int i, int j) {
        const double x = -60 + 0.5 * i, z = 0.5 * j;
        return Eigen::Vector3d(x, 1.5 + bump * std::sin(x / 3) * std::sin(z / 4), z);
      },
      [](int i, int j) {
        return std::array<uint8_t, 3>{uint8_t(100 + i % 50), 120, uint8_t(60 + j % 90)};
      });
}

TEST_F(RenderTest, LevelOfDetailKeepsTheSurfaceWithoutCracks) {
  // Far chunks simplified (beyond 10 m cells of 2 m, 4 m beyond 20 m, ...): a flat ground
  // renders the same depth
  // (clustered vertices stay on the plane), a bumpy one leaves no pixel seeing through it, and
  // far fewer triangles are drawn. Pixels are judged by where their ray meets the flat ground,
  // away from the mesh's own edges (which clustering may move).
  const Camera cam = Cam(160, 120, 120);
  const View view{cam, LookingDownZ({0, 0, 0})};
  EffectsPlan plan;
  plan.ptm = false;  // vertex colours: the surface pass alone decides
  for (double bump : {0.0, 0.3}) {
    Renderer r(Ground(bump));
    RenderStats full_stats, lod_stats;
    const Renderer::Frame full = r.Render(view, {}, plan, &full_stats, true);
    r.SetDetail(10, 2);
    const Renderer::Frame lod = r.Render(view, {}, plan, &lod_stats, true);
    // Depth maps are never simplified.
    const Image depth_map = r.RenderDepth(view);
    r.SetDetail(0, 0);
    const Renderer::Frame again = r.Render(view, {}, plan, nullptr, true);
    size_t checked = 0;
    double worst = 0;
    for (int y = 0; y < 120; ++y)
      for (int x = 0; x < 160; ++x) {
        const double dy = y + 0.5 - 60;
        if (dy < 1) continue;  // at or above the horizon
        const double z = 1.5 * 120 / dy, gx = z * (x + 0.5 - 80) / 120;
        // A cell at distance d is at most d/5 here (2 m beyond 10 m, doubling per doubling):
        // the mesh's own edges may move that far.
        if (z < 2 || z > 120 - 120 / 5.0 - 1 || std::abs(gx) > 60 - z / 5 - 1) continue;
        ++checked;
        ASSERT_FALSE(std::isinf(lod.depth.at(x, y))) << "crack at " << x << "," << y;
        ASSERT_FALSE(std::isinf(full.depth.at(x, y)));
        worst = std::max(worst, std::abs(lod.depth.at(x, y) - full.depth.at(x, y)) /
                                    double(full.depth.at(x, y)));
        ASSERT_EQ(depth_map.at(x, y), full.depth.at(x, y));
        ASSERT_EQ(again.depth.at(x, y), full.depth.at(x, y));  // back to full detail
      }
    EXPECT_GT(checked, 4000u);
    if (bump == 0) {
      EXPECT_LT(worst, 1e-4) << "a plane stays a plane";
    }
    EXPECT_LT(double(lod_stats.triangles_drawn), 0.3 * double(full_stats.triangles_drawn))
        << lod_stats.triangles_drawn << " of " << full_stats.triangles_drawn;
  }
  Renderer r(Plane(5, 10));
  EXPECT_THROW(r.SetDetail(-1, 1), Error);
  EXPECT_THROW(r.SetDetail(5, 0), Error);
}

// The projector's photo of SeenSurfacesDrawWhatTheMeshLost's scene at scale k: red (250, 0, 0)
// where it saw the box (|u − 32|, |v − 24| < 10 px), blue (0, 0, 200) on the wall; its seen map
// 5k and 10k there.
void BoxPhoto(double k, Image& img, Image& seen) {
  img = Image(64, 48, 3, 8);
  seen = Image(64, 48, 1, 32);
  for (int y = 0; y < 48; ++y)
    for (int x = 0; x < 64; ++x) {
      const bool box = std::abs(x + 0.5 - 32) < 10 && std::abs(y + 0.5 - 24) < 10;
      img.at(x, y, 0) = box ? 250.f : 0.f;
      img.at(x, y, 2) = box ? 0.f : 200.f;
      seen.at(x, y) = float((box ? 5 : 10) * k);
    }
}

// Occlusion, and seen surfaces with `seen`.
EffectsPlan SeenPlan(bool seen) {
  EffectsPlan plan;
  plan.occlusion = true;
  plan.seen = seen;
  return plan;
}

TEST_F(RenderTest, SeenSurfacesDrawWhatTheMeshLost) {
  // The world: a wall at z = 10 and a box face at z = 5, |x|, |y| < 1, in front of it; the mesh
  // has only the wall (fusion lost the box). The projector at the origin photographed both: its
  // image is red (250, 0, 0) where it saw the box (|u − 32|, |v − 24| < 10 px), blue (0, 0, 200)
  // on the wall, and its seen map (densify's) holds 5 and 10 there. A camera 1 m to the right:
  // by hand, the ray of pixel (x, y), d = ((x + ½ − 32)/50, (y + ½ − 24)/50, 1), meets the box
  // when |1 + 5·dx| < 1 and |5·dy| < 1: red with seen surfaces; without them the wall takes
  // the projector's colour where its point (1 + 10·dx, 10·dy, 10) projects (blue for most).
  // A ray that misses the box but whose wall point the projector saw only as the box (its
  // shadow) passes behind the box across an edge of the seen map (5 against 10): no seen
  // surface, the mesh's colour as without. Wall pixels the box does not touch keep the wall's
  // colour either way. The same scaled by 0.2 at UTM coordinates; and a projector without a
  // seen map changes no pixel.
  for (const auto& [k, o] : {std::pair{1.0, Eigen::Vector3d(0, 0, 0)},
                             std::pair{0.2, Eigen::Vector3d(451000.25, 5410000.75, 120.5)}}) {
    Renderer r(Plane(50 * k, 10 * k, o, 8, {0, 0, 0}));
    Image img, seen;
    BoxPhoto(k, img, seen);
    View proj{Cam(), LookingDownZ(o)};
    Image pd = r.RenderDepth(proj);
    View side{Cam(), LookingDownZ(o + Eigen::Vector3d(1 * k, 0, 0))};
    const EffectsPlan plan = SeenPlan(true), without = SeenPlan(false);
    Projector p{proj, &img, &pd, nullptr};
    p.seen = &seen;
    const Renderer::Frame a = r.Render(side, {p}, plan);
    const Renderer::Frame b = r.Render(side, {p}, without);
    // The layer cache: a projector placed first beyond the searched ranks (without its map, as
    // GatherProjectors gives it there) and then first must be searched with its map.
    Projector q = p, p2 = p;
    q.key = 7;
    p2.key = 3;
    p2.seen = nullptr;
    EffectsPlan two = plan;
    two.projectors = 2;
    r.Render(side, {q, p2}, two);
    p2.seen = &seen;
    EXPECT_EQ(r.Render(side, {p2}, plan).colour.data, a.colour.data);
    // A wall is not the ground: seen depths of any confidence count on it.
    Image unsure(64, 48, 2, 32);
    for (size_t i = 0; i < seen.pixels(); ++i)
      unsure.data[2 * i] = seen.data[i], unsure.data[2 * i + 1] = 0.1f;
    p.seen = &unsure;
    EXPECT_EQ(r.Render(side, {p}, plan).colour.data, a.colour.data);
    p.seen = nullptr;
    EXPECT_EQ(r.Render(side, {p}, plan).colour.data, b.colour.data);
    size_t box = 0, wrong_without = 0, wall = 0;
    for (int y = 0; y < 48; ++y)
      for (int x = 0; x < 64; ++x) {
        const double dx = (x + 0.5 - 32) / 50, dy = (y + 0.5 - 24) / 50;
        const double bx = std::abs(1 + 5 * dx), by = std::abs(5 * dy);
        // the wall point's place in the projector image, in box half-widths (10 px)
        const double wx = std::abs(50 * (1 + 10 * dx) / 10) / 10, wy = std::abs(50 * dy) / 10;
        if (wx > 3.1 || wy > 2.3) continue;  // the projector did not see the wall point
        if (bx < 0.9 && by < 0.9) {
          ++box;
          EXPECT_EQ(a.colour.at(x, y, 0), 250.f) << k << " " << x << "," << y;
          EXPECT_EQ(a.colour.at(x, y, 2), 0.f) << k << " " << x << "," << y;
          if (wx > 1.1 || wy > 1.1) {  // without: the wall's blue where the projector saw it
            ++wrong_without;
            EXPECT_EQ(b.colour.at(x, y, 2), 200.f) << k << " " << x << "," << y;
          }
        } else if ((bx > 1.1 || by > 1.1) && (wx > 1.1 || wy > 1.1)) {
          ++wall;
          EXPECT_EQ(a.colour.at(x, y, 2), 200.f) << k << " " << x << "," << y;
          EXPECT_EQ(a.colour.at(x, y, 0), 0.f) << k << " " << x << "," << y;
        } else if ((bx > 1.1 || by > 1.1) && wx < 0.9 && wy < 0.9) {
          EXPECT_EQ(a.colour.at(x, y, 0), b.colour.at(x, y, 0)) << k << " " << x << "," << y;
        }
      }
    EXPECT_GT(box, 150u);
    EXPECT_GT(wrong_without, 50u);
    EXPECT_GT(wall, 1000u);
  }
}

TEST_F(RenderTest, SeenSurfacesAheadOfAndBehindTheProjector) {
  // The scene of SeenSurfacesDrawWhatTheMeshLost (wall z = 10 in the mesh, box face z = 5,
  // |x|, |y| < 1, only in the projector's photo and seen map; projector at the origin), rendered
  // from cameras along the drive: 2 ahead of the projector and 3 behind it, off the axis by
  // (0.3, 0.2) (the ray's image in the projector then runs towards or away from the epipole,
  // a.z != 0, and passes it near the centre). By hand, pixel (x, y)'s ray from C is
  // C + t·((x + ½ − 32)/50, (y + ½ − 24)/50, 1): it meets the box when |C.xy + (5 − C.z)·d.xy|
  // < 1 (red), else the wall at P = C + (10 − C.z)·d, blue where the projector saw that point
  // (|P.x|, |P.y| < 6.4, 4.8, outside the box's shadow |P.xy| < 2). Then the same with no mesh
  // where the pixels look (a wall far to the side only): every pixel is sky, marched from the
  // sky distance 40, and the box's rays are red all the same. Scaled by 0.2 at UTM as well.
  for (const auto& [k, o] : {std::pair{1.0, Eigen::Vector3d(0, 0, 0)},
                             std::pair{0.2, Eigen::Vector3d(451000.25, 5410000.75, 120.5)}}) {
    Image img, seen;
    BoxPhoto(k, img, seen);
    const View proj{Cam(), LookingDownZ(o)};
    for (bool sky : {false, true}) {
      Renderer r(sky ? Plane(2 * k, 10 * k, o + Eigen::Vector3d(200 * k, 0, 0), 2)
                     : Plane(50 * k, 10 * k, o, 8, {0, 0, 0}));
      const Image pd = r.RenderDepth(proj);
      EffectsPlan plan = SeenPlan(true);
      plan.skybox = sky;
      plan.sky_distance = 40 * k;
      Projector p{proj, &img, &pd, nullptr};
      p.seen = &seen;
      for (const Eigen::Vector3d& c :
           {Eigen::Vector3d(0.3, 0.2, 2), Eigen::Vector3d(0.3, 0.2, -3)}) {
        const Renderer::Frame a = r.Render({Cam(), LookingDownZ(o + k * c)}, {p}, plan);
        size_t box = 0, wall = 0;
        for (int y = 0; y < 48; ++y)
          for (int x = 0; x < 64; ++x) {
            const Eigen::Vector2d d((x + 0.5 - 32) / 50, (y + 0.5 - 24) / 50);
            const Eigen::Vector2d b = (c.head<2>() + (5 - c.z()) * d).cwiseAbs();
            const Eigen::Vector2d w = (c.head<2>() + (10 - c.z()) * d).cwiseAbs();
            const std::string at = std::to_string(k) + " " + std::to_string(sky) + " " +
                                   std::to_string(c.z()) + " " + std::to_string(x) + "," +
                                   std::to_string(y);
            if (b.maxCoeff() < 0.75) {  // 2.5 px inside the box in the projector: a sample
              ++box;                    // every 2 px may step over a crossing nearer its edge
              EXPECT_EQ(a.colour.at(x, y, 0), 250.f) << at;
              EXPECT_EQ(a.colour.at(x, y, 2), 0.f) << at;
            } else if (b.minCoeff() > 1.1 && w.x() < 6 && w.y() < 4.4 && w.maxCoeff() > 2.2) {
              ++wall;
              EXPECT_EQ(a.colour.at(x, y, 2), 200.f) << at;
              EXPECT_EQ(a.colour.at(x, y, 0), 0.f) << at;
            }
          }
        EXPECT_GT(box, 60u) << k << " " << c.z();
        EXPECT_GT(wall, 300u) << k << " " << c.z();
      }
    }
  }
}

TEST_F(RenderTest, SeenSurfacesOnTheGroundNeedConfidence) {
  // A flat ground 1.5 below the cameras (y down: the render camera's up is −y), nothing else.
  // The projector at the origin photographed red on a patch of it from 3.2 ahead to 7.1 (rows
  // 34..47, down to the image's bottom row; |u − 32| < 12) and blue elsewhere; its seen map
  // holds the ground's depth, but 0.75 of it on the patch: a false surface in front of the road,
  // as a repetitive marking matched a period off gives. Rendered from 1 m to the right: with the
  // false depths sure (confidence 0.9) ground pixels beside the patch take its red where they
  // showed blue; unsure (0.3, below the default floor 0.6) the frame is the one without seen
  // surfaces, pixel for pixel (the bottom row included); with the floor at 0 the unsure map acts as
  // the sure one. The same plane 1.5 above the cameras is a ceiling, not the ground: there the
  // unsure map acts as the sure one at the default floor. Also scaled by 0.2 at UTM coordinates,
  // and that world turned by 0.3 rad about (1, 2, 3) with the cameras (their up turns with them).
  const Eigen::Matrix3d turn =
      Eigen::AngleAxisd(0.3, Eigen::Vector3d(1, 2, 3).normalized()).toRotationMatrix();
  struct World {
    double k;
    Eigen::Vector3d o;
    Eigen::Matrix3d q;  // world from the unturned world
  };
  const Eigen::Vector3d utm(451000.25, 5410000.75, 120.5);
  for (const World& w : {World{1.0, Eigen::Vector3d::Zero(), Eigen::Matrix3d::Identity()},
                         World{0.2, utm, Eigen::Matrix3d::Identity()}, World{0.2, utm, turn}})
    for (double below : {1.0, -1.0}) {
      auto at = [&](const Eigen::Vector3d& x) -> Eigen::Vector3d { return w.o + w.q * (w.k * x); };
      auto camera = [&](const Eigen::Vector3d& c) {
        const Eigen::Matrix3d qt = w.q.transpose();
        return View{Cam(), Rigid3d(Eigen::Quaterniond(qt), -(qt * at(c)))};
      };
      Renderer r(Grid(
          8, 8,
          [&](int i, int j) {
            return at({-20.0 + 5 * i, 1.5 * below, 1.0 + 5 * j});
          },
          [](int, int) {
            return std::array<uint8_t, 3>{0, 90, 0};
          }));
      const View proj = camera({0, 0, 0});
      const Image pd = r.RenderDepth(proj);
      Image img(64, 48, 3, 8);
      auto patch = [below](int x, int y) {
        return std::abs(x + 0.5 - 32) < 12 && (below > 0 ? y >= 34 : y < 14);
      };
      for (int y = 0; y < 48; ++y)
        for (int x = 0; x < 64; ++x) {
          img.at(x, y, 0) = patch(x, y) ? 250.f : 0.f;
          img.at(x, y, 2) = patch(x, y) ? 0.f : 200.f;
        }
      auto map = [&](float confidence) {
        Image m(64, 48, 2, 32);
        for (int y = 0; y < 48; ++y)
          for (int x = 0; x < 64; ++x) {
            m.at(x, y, 0) = pd.at(x, y) * (patch(x, y) ? 0.75f : 1.f);
            m.at(x, y, 1) = confidence;
          }
        return m;
      };
      const Image sure = map(0.9f), unsure = map(0.3f);
      const View side = camera({1, 0, 0});
      const EffectsPlan plan = SeenPlan(true), without = SeenPlan(false);
      Projector p{proj, &img, &pd, nullptr};
      const Renderer::Frame b = r.Render(side, {p}, without);
      p.seen = &sure;
      const Renderer::Frame a = r.Render(side, {p}, plan);
      const std::string at_k = std::to_string(w.k) + " " + std::to_string(below);
      // Pixels changed; of those, the full red (all but a few at the red's bilinear edge).
      size_t taken = 0, red = 0;
      for (size_t i = 0; i < a.colour.pixels(); ++i)
        if (a.colour.data[3 * i] != b.colour.data[3 * i]) {
          ++taken;
          red += a.colour.data[3 * i] == 250.f;
        }
      EXPECT_GT(red, 20u) << at_k;
      EXPECT_GE(red + 5, taken) << at_k;
      p.seen = &unsure;
      EXPECT_EQ(r.Render(side, {p}, plan).colour.data, (below > 0 ? b : a).colour.data) << at_k;
      EffectsPlan any = plan;
      any.seen_surfaces.ground_confidence = 0;
      EXPECT_EQ(r.Render(side, {p}, any).colour.data, a.colour.data) << at_k;
    }
}

TEST_F(RenderTest, BadInputsAreClearErrors) {
  EXPECT_THROW({ Renderer r{Mesh()}; }, Error);
  Renderer r(Plane(5, 10));
  Image a = Pattern(64, 48), b = Pattern(32, 24);
  View v{Cam(), LookingDownZ({0, 0, 0})};
  Projector pa{v, &a, nullptr, nullptr},
      pb{View{Cam(32, 24, 25), v.world_to_camera}, &b, nullptr, nullptr};
  EffectsPlan plan;
  plan.projectors = 2;
  try {
    r.Render(v, {pa, pb}, plan);
    FAIL();
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("differ in size"), std::string::npos) << e.what();
  }
  Projector wrong{v, &b, nullptr, nullptr};  // image size ≠ camera size
  EXPECT_THROW(r.Render(v, {wrong}, EffectsPlan()), Error);
  View distorted{ParseCameraSpec("OPENCV 64 48 50 50 32 24 0.1 0 0 0"), v.world_to_camera};
  EXPECT_THROW(r.RenderDepth(distorted), Error);
}

TEST_F(RenderTest, ShaderErrorsNameFileVariantAndLine) {
  // A zero-sized projector array is a compile error in ptm_common.glsl; the message must point
  // at that file and line (found here independently, by searching the file) and the variant.
  const std::string& src = ShaderSource("ptm_common.glsl");
  int line = 1;
  for (size_t i = 0; i < src.find("uniform mat3 u_proj_R[MVTM_MAX_PROJECTORS]"); ++i)
    line += src[i] == '\n';
  try {
    BuildProgram("mesh.vert", "ptm.frag", {"MVTM_MAX_PROJECTORS 0", "MVTM_PTM"},
                 {"ptm_common.glsl"});
    FAIL() << "no compile error";
  } catch (const Error& e) {
    std::string want =
        "shaders/ptm_common.glsl:" + std::to_string(line) + " [MVTM_MAX_PROJECTORS 0 MVTM_PTM]: ";
    EXPECT_EQ(std::string(e.what()).substr(0, want.size()), want) << e.what();
  }
}

TEST_F(RenderTest, ContextCanBeRecreated) {
  // Several contexts in sequence in one process (the suite's own context is released first).
  delete ctx_;
  ctx_ = nullptr;
  for (int i = 0; i < 3; ++i) {
    auto c = GlContext::Create();
    Renderer r(Plane(5, 10));
    EXPECT_NEAR(r.RenderDepth({Cam(), LookingDownZ({0, 0, 0})}).at(32, 24), 10.0, 1e-5);
  }
  auto os = GlContext::Create(GlBackend::kOsMesa);
  EXPECT_NE(os->Describe().find("OSMesa"), std::string::npos);
  Renderer r(Plane(5, 10));
  EXPECT_NEAR(r.RenderDepth({Cam(), LookingDownZ({0, 0, 0})}).at(32, 24), 10.0, 1e-5);
  os.reset();
  ctx_ = GlContext::Create().release();
}

}  // namespace
}  // namespace mvtm
