// mvtm — loading a workspace's images as projectors: colour image, depth map, mask (the
// workspace side of rendering: libcore/render itself knows no folders).
//
// Shared by ptmrender and inpaint3d. Images are looked up by their index in a list of the
// model's images (ImagesByName order). Depth maps come from the workspace's baked depth/ (resized
// to the image size, nearest neighbour, when baked at another --scale) or, when not baked, are
// rendered with the Renderer given (Error when there is none). Everything is cached; Trim() drops
// the least recently used items beyond `capacity` and must only be called between frames, since
// the returned references point into the caches. Prefetch() reads the next frame's files on a
// second thread while this one renders.
//
// Thread safety: one thread calls the methods (the one holding the Renderer's GL context); the
// prefetch thread only reads files.
#pragma once

#include <array>
#include <cstdint>
#include <exception>
#include <future>
#include <map>
#include <set>
#include <string>
#include <vector>

#include "io/exposure_tsv.h"
#include "render/effects_plan.h"
#include "render/renderer.h"
#include "scene/reconstruction.h"
#include "workspace/assets.h"
#include "workspace/workspace.h"

namespace mvtm {

// WS/exposure.tsv by image name; empty when the workspace has none. Throws Error when malformed.
std::map<std::string, ExposureRow> ReadWorkspaceExposure(const Workspace& ws);
// Whether an exposure changes a projector's samples at the renderer's (float) precision.
bool ChangesSamples(const ExposureRow& e);

class ProjectorSources {
 public:
  // prefer_textures: read textures/NAME (vehicles removed) when it exists, else images/NAME.
  ProjectorSources(const Workspace& ws, const Reconstruction& rec,
                   std::vector<const ImageRecord*> images, Renderer* renderer, bool prefer_textures,
                   size_t capacity = 32);
  void SetRenderer(Renderer* renderer) { renderer_ = renderer; }

  const Image& ImageOf(size_t k);
  const Image& DepthOf(size_t k);
  const Image* MaskOf(size_t k);  // nullptr when the image has no mask file
  // densify's map of what the photo saw (stereo/NAME.exr) at the image's size with its
  // confidence as a second channel (ReadSeenDepthAtCamera); nullptr when the workspace has none
  // for the image.
  const Image* SeenOf(size_t k);
  // The image's exposure from WS/exposure.tsv (gain 1, offset 0 when absent); true when it is
  // not the identity.
  bool ExposureOf(size_t k, CameraExposure& exposure);
  View ViewOf(size_t k) const;
  void Trim();
  // Starts reading the files of the images `ks` that are not cached (colour; with `depth` the
  // baked depth map, with `mask` the mask, for the first `seen` densify's map) on a second thread;
  // ImageOf, DepthOf, MaskOf and SeenOf take them from there (an error reading one is thrown by
  // the call that asks for it). Waits for the previous batch first.
  void Prefetch(const std::vector<size_t>& ks, bool depth, bool mask, int seen = 0);
  ~ProjectorSources();

 private:
  // A cached item: the image (empty: no mask file) and when it was last asked for.
  struct Entry {
    Image image;
    uint64_t used = 0;
  };
  // One read of a file: its image, or the error reading it.
  struct Read {
    Image image;
    std::exception_ptr error;
  };
  using Cache = std::map<size_t, Entry>;
  using Batch = std::map<size_t, Read>;
  // The file readers (const: the prefetch thread calls them too).
  Image ReadColour(size_t k) const;
  Image ReadDepthFile(size_t k) const;  // empty when there is no baked depth map
  Image ReadMaskFile(size_t k) const;   // empty when there is no mask file
  Image ReadSeenFile(size_t k) const;   // empty when there is no densify map
  // The cached item k, read by `read` unless cached or prefetched.
  const Image& Get(Cache& cache, Batch& prefetched, size_t k,
                   Image (ProjectorSources::*read)(size_t) const);
  void TakePrefetched();

  const Workspace& ws_;
  const Reconstruction& rec_;
  std::vector<const ImageRecord*> images_;
  Renderer* renderer_;
  bool prefer_textures_;
  size_t capacity_;
  uint64_t tick_ = 0;
  Cache image_, depth_, mask_, seen_;
  std::future<std::array<Batch, 4>> prefetch_;  // colour, depth, mask, seen
  std::array<Batch, 4> prefetched_;
  std::map<std::string, ExposureRow> exposure_;  // exposure.tsv, read on first use
  bool exposure_read_ = false;
};

// The projectors of one frame: the images `indices` (best first) with what `plan` needs (their
// depth maps for occlusion or the skybox, masks, exposures, densify's maps for seen surfaces). The
// references point into `sources` until its next Trim(). `depth_ms` (optional) accumulates the time
// spent gathering depth maps.
std::vector<Projector> GatherProjectors(ProjectorSources& sources,
                                        const std::vector<size_t>& indices, const EffectsPlan& plan,
                                        double* depth_ms = nullptr);

// The exposure a camera at `centre` records at: its projectors' exposures weighted by inverse
// squared distance (a projector at the centre itself alone); the identity without projectors.
CameraExposure ExposureNear(const std::vector<Projector>& projectors,
                            const Eigen::Vector3d& centre);

// The name of the first of `images[used]` whose mask has a set pixel ("" when none): the example
// that plans the masks effect.
std::string FirstMaskedImage(const Workspace& ws, const std::vector<const ImageRecord*>& images,
                             const std::set<size_t>& used);
// The name of the first of `images[used]` with a densify map (stereo/NAME.exr; "" when none).
std::string FirstSeenImage(const Workspace& ws, const std::vector<const ImageRecord*>& images,
                           const std::set<size_t>& used);
// The name of the first of `images[used]` whose exposure (exposure.tsv) changes its samples.
std::string FirstExposedImage(const Workspace& ws, const std::vector<const ImageRecord*>& images,
                              const std::set<size_t>& used);

}  // namespace mvtm
