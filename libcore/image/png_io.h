// mvtm — PNG reading through libpng itself, the pipeline's hot path.
//
// Pixels are exactly what OpenImageIO's PNG reader gives with unassociated alpha (checked by
// tests/unit/image/png_io_test.cpp): palettes expanded to RGB, a tRNS chunk to an alpha
// channel, 1/2/4-bit grey scaled to 8 bits, 16-bit samples kept, no gamma applied.
// What this adds: libpng's own error and warning texts never reach stderr (they become one
// Error naming the file), and an image header is not trusted with an allocation beyond
// kMaxReadImageSide / kMaxImagePixels.
#pragma once

#include <string>
#include <vector>

#include "image/image.h"

namespace mvtm {

// True when the file starts with the PNG signature (false for a missing or short file).
bool IsPngFile(const std::string& path);

// Reads a PNG. `header_only` fills width/height/channels/bits and leaves the pixels empty.
// Throws Error(path, 0, "...") for a corrupt, truncated or oversized file.
Image ReadPng(const std::string& path, bool header_only = false);

// Encodes an 8- or 16-bit image of 1 to 4 channels (grey, grey+alpha, RGB, RGBA) as PNG bytes,
// with OpenImageIO 2.4's settings, so the bytes are the ones its PNG writer produced for mvtm
// (checked by png_io_test): zlib level 6 with the default strategy, libpng's adaptive filters,
// an oFFs chunk (0, 0) and a tIME chunk fixed at 1970-01-01 00:00:00 (no clock in the output).
// Samples are rounded to nearest and clamped; colour is written as stored (unassociated alpha,
// so a PNG read and written again keeps its pixels). PngCompression::kFast trades those bytes
// for speed (image.h). Throws Error(path, 0, ...).
std::vector<unsigned char> EncodePng(const std::string& path, const Image& img,
                                     PngCompression compression = PngCompression::kDefault);

}  // namespace mvtm
