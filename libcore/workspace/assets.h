// mvtm — a workspace's per-image files read at their camera's size: the one place that knows how
// an image, its texture, baked depth map, mask and labels relate to the camera that took it.
//
// Every tool reading per-image files goes through these (ProjectorSources caches and prefetches
// them for the renderers; gazemap and pickview read through them), so a workspace baked at any
// `bakedepth --scale` reads alike everywhere: a depth map of another size but the camera's aspect
// (within a pixel) is resized to the camera's size, nearest neighbour (depth must not be blended
// across edges); any other size is an Error naming the file. Colour images, masks and labels must
// be the camera's size. Functions returning an empty Image mean "no such file".
// Thread safety: plain functions, safe from any thread.
#pragma once

#include <string>

#include "camera/camera.h"
#include "image/image.h"
#include "workspace/workspace.h"

namespace mvtm {

// textures/NAME when `prefer_textures` and it exists, else images/NAME; the camera's size.
Image ReadSourceImage(const Workspace& ws, const std::string& name, const Camera& cam,
                      bool prefer_textures);
// depth/NAME.exr at the camera's size; empty when not baked.
Image ReadDepthAtCamera(const Workspace& ws, const std::string& name, const Camera& cam);
// stereo/NAME.exr (densify's map of what the photo saw) at the camera's size, nearest
// neighbour, with its confidence (stereo/NAME.conf.exr; 1 without one) as a second channel;
// empty when the workspace has none for the image. A densify killed between the pair's renames
// is finished first (FinishInterruptedWrites), so the two are always of one run.
Image ReadSeenDepthAtCamera(const Workspace& ws, const std::string& name, const Camera& cam);
// masks/NAME.png (0 or 255) at the camera's size; empty when the image has no mask.
Image ReadMaskAtCamera(const Workspace& ws, const std::string& name, const Camera& cam);
// labels/NAME.png at the camera's size; empty when the image has no labels.
Image ReadLabelsAtCamera(const Workspace& ws, const std::string& name, const Camera& cam);

// Nearest-neighbour resize (for depth maps baked at another scale).
Image ResizeNearest(const Image& d, int w, int h);

}  // namespace mvtm
