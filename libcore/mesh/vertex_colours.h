// mvtm — vertex colours baked from photographs: the weighted mean of the images that see each
// vertex (the Lambertian baseline of thesis §4.2.5; roadmesh).
//
// For each image, a vertex counts when it is at least 0.1 in front of the camera, projects inside
// the image, is not hidden (its depth is at most 1.01 × the farthest mesh depth in the 3×3 pixels
// around it + 0.02: depth maps rendered through render/renderer.h, so silhouettes and grazing
// angles are kept) and faces the camera (cosine between its normal and the direction to the
// camera above 0.02). Its sample is the bilinear image value at the projection (pixel centres at
// +0.5; grey images give grey colours), weighted by cosine / distance. Unseen vertices take the
// colour of their seen neighbours: the mean of the already coloured vertices they share an edge
// with, front by front outwards from the seen ones (never black); a part of the mesh no image
// sees anywhere stays mid grey (128).
//
// Conventions: poses are COLMAP's (world-to-camera; the quaternion is normalised here); cameras
// undistorted (PINHOLE / SIMPLE_PINHOLE), scaled to the image when its size differs; images in
// their file's scale (8-bit, 16-bit or float), colours 8-bit. Distances in the model's own unit.
// Ownership: the baker keeps a copy of the mesh on the GPU and its own sums; the mesh passed to
// Finish() may be the same object.
// Thread safety: a baker belongs to the thread holding the GL context (render/context.h).
#pragma once

#include <Eigen/Core>
#include <cstddef>
#include <memory>
#include <vector>

#include "camera/camera.h"
#include "geometry/rigid.h"
#include "image/image.h"
#include "scene/mesh.h"

namespace mvtm {

class Renderer;

class VertexColourBaker {
 public:
  // Uploads `mesh` (vertices, faces and normals: Error without normals or faces). A GL context
  // must be current; `mesh` must outlive the baker and not change while it is used.
  explicit VertexColourBaker(const Mesh& mesh);
  ~VertexColourBaker();
  VertexColourBaker(const VertexColourBaker&) = delete;
  VertexColourBaker& operator=(const VertexColourBaker&) = delete;

  // Adds one photograph taken by `camera` at `world_to_camera`. `mask` (empty, or 1 channel of
  // the image's size, non-zero = leave out: a vehicle, an overlay) takes its pixels out of the
  // colours. Throws Error for a distorted camera model or a mask of another size.
  void Add(const Camera& camera, const Rigid3d& world_to_camera, const Image& image,
           const Image& mask = Image());

  // Writes the colours into `mesh` (same vertices as the baker's); returns the number of vertices
  // seen by at least one image.
  size_t Finish(Mesh& mesh) const;

 private:
  const Mesh& mesh_;
  std::unique_ptr<Renderer> renderer_;
  std::vector<Eigen::Vector3d> sum_;
  std::vector<double> weight_;
};

}  // namespace mvtm
