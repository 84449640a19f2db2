#include "mesh/vertex_colours.h"

#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <cstdint>

#include "base/error.h"
#include "render/renderer.h"

namespace mvtm {

namespace {

// Visible when no surface is nearer: the farthest depth around the pixel absorbs silhouettes and
// grazing angles.
bool Visible(const Image& depth, int ix, int iy, double z) {
  float dmax = 0;
  for (int yy = std::max(0, iy - 1); yy <= std::min(depth.height - 1, iy + 1); ++yy)
    for (int xx = std::max(0, ix - 1); xx <= std::min(depth.width - 1, ix + 1); ++xx) {
      const float d = depth.at(xx, yy);
      if (std::isfinite(d)) dmax = std::max(dmax, d);
    }
  return !(z > dmax * 1.01 + 0.02);
}

// Bilinear sample (pixel centres at +0.5) of the first three channels, or of the only one.
Eigen::Vector3d Bilinear(const Image& img, const Eigen::Vector2d& px) {
  const int nc = img.channels >= 3 ? 3 : 1;
  const double fx = std::clamp(px.x() - 0.5, 0.0, img.width - 1.0),
               fy = std::clamp(px.y() - 0.5, 0.0, img.height - 1.0);
  const int x0 = static_cast<int>(fx), y0 = static_cast<int>(fy);
  const int x1 = std::min(x0 + 1, img.width - 1), y1 = std::min(y0 + 1, img.height - 1);
  const double ax = fx - x0, ay = fy - y0;
  Eigen::Vector3d c;
  for (int ch = 0; ch < 3; ++ch) {
    const int cc = nc == 3 ? ch : 0;
    c[ch] = (1 - ay) * ((1 - ax) * img.at(x0, y0, cc) + ax * img.at(x1, y0, cc)) +
            ay * ((1 - ax) * img.at(x0, y1, cc) + ax * img.at(x1, y1, cc));
  }
  return c;
}

}  // namespace

VertexColourBaker::VertexColourBaker(const Mesh& mesh) : mesh_(mesh) {
  if (!mesh.has_normals()) throw Error("vertex colours: the mesh has no normals");
  renderer_ = std::make_unique<Renderer>(mesh);
  sum_.assign(mesh.vertices.size(), Eigen::Vector3d::Zero());
  weight_.assign(mesh.vertices.size(), 0.0);
}

VertexColourBaker::~VertexColourBaker() = default;

void VertexColourBaker::Add(const Camera& camera, const Rigid3d& world_to_camera, const Image& img,
                            const Image& mask) {
  camera.RequireUndistorted();
  if (!mask.data.empty() && (mask.width != img.width || mask.height != img.height))
    throw Error("vertex colours: the mask is not of the image's size");
  Camera cam = camera;
  if (uint64_t(img.width) != cam.width || uint64_t(img.height) != cam.height)
    cam = cam.Scaled(uint64_t(img.width), uint64_t(img.height));
  const Rigid3d pose(NormalizedQuaternion(world_to_camera.q), world_to_camera.t);
  const Eigen::Vector3d centre = pose.Centre();
  const Image depth = renderer_->RenderDepth(View{cam, world_to_camera});
  const double scale = 255.0 / img.MaxValue();
  for (size_t v = 0; v < mesh_.vertices.size(); ++v) {
    const Eigen::Vector3d x = pose * mesh_.vertices[v];
    if (x.z() < 0.1) continue;
    const Eigen::Vector2d px = cam.Project(x);
    const int ix = static_cast<int>(std::floor(px.x())), iy = static_cast<int>(std::floor(px.y()));
    if (ix < 0 || iy < 0 || ix >= img.width || iy >= img.height) continue;
    if (!mask.data.empty() &&
        mask.data[(size_t(iy) * size_t(mask.width) + size_t(ix)) * size_t(mask.channels)] != 0)
      continue;
    if (!Visible(depth, ix, iy, x.z())) continue;
    const Eigen::Vector3d to_cam = centre - mesh_.vertices[v];
    const double dist = to_cam.norm();
    const double cosv = mesh_.normals[v].cast<double>().dot(to_cam) / dist;
    if (cosv <= 0.02) continue;
    const double w = cosv / dist;
    sum_[v] += w * scale * Bilinear(img, px);
    weight_[v] += w;
  }
}

size_t VertexColourBaker::Finish(Mesh& mesh) const {
  if (mesh.vertices.size() != sum_.size())
    throw Error("vertex colours: the mesh is not the one baked");
  const size_t n = mesh.vertices.size();
  std::vector<Eigen::Vector3d> colour(n, Eigen::Vector3d::Constant(128.0));
  std::vector<uint8_t> known(n, 0);
  size_t coloured = 0;
  for (size_t v = 0; v < n; ++v)
    if (weight_[v] > 0) {
      colour[v] = sum_[v] / weight_[v];
      known[v] = 1;
      ++coloured;
    }
  // Unseen vertices take the mean colour of their already coloured neighbours, front by front
  // outwards from the seen ones (a vertex's front is its edge distance to the nearest seen one).
  std::vector<std::vector<uint32_t>> nbr(n);
  for (const auto& f : mesh.faces)
    for (int i = 0; i < 3; ++i) {
      nbr[f[size_t(i)]].push_back(f[size_t((i + 1) % 3)]);
      nbr[f[size_t((i + 1) % 3)]].push_back(f[size_t(i)]);
    }
  // Each round colours the unseen neighbours of the vertices the last round coloured (the first
  // round: of the seen ones), from the colours known before the round.
  std::vector<uint32_t> last;
  for (size_t v = 0; v < n; ++v)
    if (known[v]) last.push_back(uint32_t(v));
  while (!last.empty()) {
    std::vector<uint32_t> front;
    for (uint32_t v : last)
      for (uint32_t u : nbr[v])
        if (!known[u]) front.push_back(u);
    std::sort(front.begin(), front.end());
    front.erase(std::unique(front.begin(), front.end()), front.end());
    std::vector<Eigen::Vector3d> mean(front.size(), Eigen::Vector3d::Zero());
    for (size_t i = 0; i < front.size(); ++i) {
      int k = 0;
      for (uint32_t u : nbr[front[i]])
        if (known[u]) mean[i] += colour[u], ++k;
      mean[i] /= k;  // k >= 1: a front vertex neighbours a coloured one
    }
    for (size_t i = 0; i < front.size(); ++i) {
      colour[front[i]] = mean[i];
      known[front[i]] = 1;
    }
    last = std::move(front);
  }
  mesh.colors.resize(n);
  for (size_t v = 0; v < n; ++v)
    for (int ch = 0; ch < 3; ++ch)
      mesh.colors[v][size_t(ch)] =
          static_cast<uint8_t>(std::lround(std::clamp(colour[v][ch], 0.0, 255.0)));
  return coloured;
}

}  // namespace mvtm
