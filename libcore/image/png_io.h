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

#include "image/image.h"

namespace mvtm {

// True when the file starts with the PNG signature (false for a missing or short file).
bool IsPngFile(const std::string& path);

// Reads a PNG. `header_only` fills width/height/channels/bits and leaves the pixels empty.
// Throws Error(path, 0, "...") for a corrupt, truncated or oversized file.
Image ReadPng(const std::string& path, bool header_only = false);

}  // namespace mvtm
