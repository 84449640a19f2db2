// mvtm — masks: which pixels of an image are set (a vehicle to remove, a region to compare).
//
// One rule everywhere: a pixel is set when ANY channel of the mask file is non-zero. Masks in a
// workspace are 8-bit one-channel PNGs with 0 and 255 (segtrack writes them so), but a mask
// drawn in an editor as RGB or grey-with-alpha, or saved with values 1 for "set", means the same.
// In memory a mask is an 8-bit one-channel Image holding exactly 0 or 255.
#pragma once

#include <cstddef>
#include <string>

#include "image/image.h"

namespace mvtm {

// The mask of an image under the rule above: one channel, 0 or 255, same size.
Image MaskFromImage(const Image& img);
// Reads a mask file (any format the image layer reads). Throws Error naming the file.
Image ReadMask(const std::string& path);
// Number of set pixels of a mask made by MaskFromImage/ReadMask.
size_t CountSet(const Image& mask);

}  // namespace mvtm
