// mvtm — projective texture mapping and depth rendering of a mesh (libcore/render).
//
// Conventions:
//  * Views are COLMAP cameras (PINHOLE / SIMPLE_PINHOLE only) with world-to-camera poses; the
//    OpenGL axis flip happens here and nowhere else.
//  * Precision: the mesh is split into spatial chunks, each stored as float offsets from its own
//    double-precision origin; every frame is drawn camera-relative (chunk origin − camera centre
//    is computed in double), so a road at UTM coordinates renders like one at the origin.
//    Projector transforms are likewise built in double relative to the render camera.
//  * Depth maps are linear camera-space z (float32 metres), +inf where there is no surface.
//  * Images are float samples 0..255 (8-bit scale), row 0 at the top, like libcore/image.
//  * Chunks outside the view frustum are not drawn (frustum culling in double on the CPU); far
//    ones may be drawn simplified (SetDetail: a live renderer's level of detail).
//
// Thread safety: a Renderer belongs to the thread holding the GL context.
#pragma once

#include <array>
#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include "camera/camera.h"
#include "geometry/rigid.h"
#include "image/image.h"
#include "render/effects_plan.h"
#include "scene/mesh.h"

namespace mvtm {

struct View {
  Camera camera;  // undistorted
  Rigid3d world_to_camera;
};

// A camera's exposure, I = gain · L + offset (8-bit scale; radiometry/exposure.h): a projector's
// photo was recorded at one, a render records at one (with plan.exposure); the identity is the
// workspace's common exposure.
struct CameraExposure {
  float gain = 1.f, offset = 0.f;
};

struct Projector {
  View view;
  const Image* image = nullptr;  // 1 or 3 (or 4) channels, 8-bit scale, size = camera size
  const Image* depth = nullptr;  // linear depth, any size (nearest lookup); nullptr = none
  const Image* mask = nullptr;   // 8-bit, non-zero = do not use; nullptr = none
  // Identity of the (image, depth, mask, seen) set, e.g. the image's index in the workspace; when
  // every projector of a frame has a key ≥ 0 and the keys equal the previous frame's, the
  // textures already on the GPU are reused instead of uploaded again.
  int64_t key = -1;
  // The image's exposure: with plan.exposure its samples are brought to the common frame,
  // (I − offset) / gain.
  CameraExposure exposure{};
  // What the photo saw (densify's map): linear depth, size = image size, and optionally its
  // confidence 0..1 as a second channel (1 without); nullptr = none (with plan.seen: nothing
  // seen in front of the mesh).
  const Image* seen = nullptr;
};

struct RenderStats {
  size_t chunks_drawn = 0, chunks_total = 0, triangles_drawn = 0;
  double cull_ms = 0, draw_ms = 0, readback_ms = 0;
  double shade_ms = 0;  // Render's second pass: texturing each pixel once
  double fill_ms = 0;   // the push-pull fill (plan.fill)
};

// What a frame's pixels came from: 0..K−1 projector rank (with blending: the heaviest), 253
// filled from the surrounding pixels (plan.fill), 254 vertex colour, 255 background.
inline constexpr uint8_t kSourceFilled = 253, kSourceVertex = 254, kSourceBackground = 255;

class Renderer {
 public:
  // Uploads the mesh (chunks of about `chunk_size` metres). A GL context must be current.
  // Throws Error for an empty mesh (no faces).
  explicit Renderer(const Mesh& mesh, double chunk_size = 12.0);
  ~Renderer();
  Renderer(const Renderer&) = delete;
  Renderer& operator=(const Renderer&) = delete;

  // Linear camera-space depth of the mesh seen from `view` (1 channel, bits 32), +inf = none.
  Image RenderDepth(const View& view, RenderStats* stats = nullptr);

  struct Frame {
    Image colour;  // 3 channels, 8-bit scale (rounded)
    Image source;  // 1 channel: projector rank / kSourceVertex / kSourceBackground
    Image depth;   // with_depth: what RenderDepth(view) gives, from the same pass; else empty
  };
  // Renders `view` with the projectors (rank order) under `plan`. Projector images must all
  // have the same size (Error otherwise); depth maps are needed when plan.occlusion or
  // plan.skybox (sky is taken only where a projector sees no surface), masks when
  // plan.masks (a projector without one is treated as unmasked).
  // Two passes: the mesh once for the surface each pixel sees, then the texturing once per pixel.
  // The skybox changes only pixels with no surface (those where depth is +inf); so does the fill
  // (plan.fill: the pixels left at the background are filled by push-pull, render/fill.h).
  Frame Render(const View& view, const std::vector<Projector>& projectors, const EffectsPlan& plan,
               RenderStats* stats = nullptr, bool with_depth = false,
               CameraExposure exposure = CameraExposure());

  // Level of detail for Render's frames (never RenderDepth's depth maps): chunks whose box is
  // farther than `distance` (model units) from the camera are drawn simplified by vertex
  // clustering (Rossignac & Borrel 1993) on a world grid of `cell` model units, beyond twice
  // the distance of 2·cell, four times 4·cell, eight times 8·cell (a constant angular error);
  // vertices on a chunk's border never move, so chunks of different levels meet without
  // cracks. The mesh's own open edges may move by up to a cell (a fused mesh is ragged: keeping
  // them would keep most of it). Distance 0: full detail everywhere (the default). The
  // simplified meshes are built once per cell size and kept (the first call with a cell size
  // costs a pass over the mesh; later ones with it cost nothing).
  // Throws Error for a negative distance or a cell <= 0 with a distance.
  void SetDetail(double distance, double cell);

  size_t triangles() const;
  size_t chunks() const;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace mvtm
