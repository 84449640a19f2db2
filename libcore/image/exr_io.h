// mvtm — OpenEXR reading and writing through the OpenEXR library itself (depth and confidence
// maps, float renders: the pipeline's hot path), without OpenImageIO.
//
// What is read here: single-part scanline or tiled files (level 0) whose channels are all HALF
// or all FLOAT, unsubsampled, and either one channel of any name or R,G[,B[,A]]. Samples come
// back as 32-bit floats in R,G,B,A order, exactly as OpenImageIO gives them (checked by
// tests/unit/image/image_formats_test.cpp). Anything else (multi-part, deep, UINT channels,
// other channel sets) is left to OpenImageIO: ReadExr returns false.
// What is written: FLOAT channels named as OpenImageIO 2.4 names them (Y; R,G; R,G,B; R,G,B,A),
// ZIP compression, the default OpenEXR header and capDate "1970:01:01 00:00:00", so the bytes
// are the ones OpenImageIO wrote for mvtm (no clock in the output).
#pragma once

#include <string>
#include <vector>

#include "image/image.h"

namespace mvtm {

// True when the file starts with the OpenEXR magic number (false for a missing or short file).
bool IsExrFile(const std::string& path);

// Reads `path` into `img` (header only when `header_only`: width, height, channels, bits = 32)
// and returns true, or returns false when the file is a kind this reader leaves to OpenImageIO.
// Throws Error(path, 0, "cannot read image: ...") for a corrupt, truncated or oversized file.
bool ReadExr(const std::string& path, bool header_only, Image* img);

// Encodes a 32-bit image of 1 to 4 channels. Throws Error(path, 0, ...).
std::vector<unsigned char> EncodeExr(const std::string& path, const Image& img);

}  // namespace mvtm
