// mvtm — filling unknown pixels from the known ones around them: push-pull (Gortler et al. 1996,
// "The Lumigraph" §3.4).
//
// Pull: an image pyramid of weighted means, each coarser pixel the mean of the 2×2 finer pixels
// it covers, weighted by how much of each is known (weights summed, capped at 1). Push: from the
// coarsest level down, each pixel keeps its own colour in proportion to its weight and takes the
// rest from the coarser level's bilinear interpolation. An unknown pixel so gets a smooth mean of
// the known pixels nearest it, at whatever scale they are found; known pixels are unchanged.
//
// Thread safety: pure function.
#pragma once

#include <cstdint>
#include <vector>

#include "image/image.h"

namespace mvtm {

// Fills the pixels of `img` where known[pixel] == 0 (every channel). Returns false, with `img`
// unchanged, when no pixel is known. `known` holds img.pixels() entries (Error otherwise).
bool PushPullFill(Image& img, const std::vector<uint8_t>& known);

}  // namespace mvtm
