// mvtm — JPEG reading through libjpeg-turbo itself (camera photos: the pipeline's input),
// without OpenImageIO.
//
// Grey and YCbCr/RGB 8-bit JPEGs are decoded with libjpeg's defaults (accurate integer DCT,
// fancy upsampling), which gives exactly OpenImageIO's pixels (checked by
// tests/unit/image/image_formats_test.cpp); CMYK and YCCK files are left to OpenImageIO
// (ReadJpeg returns false). A file cut short is an error (libjpeg alone would fill the missing
// rows with grey and only warn).
#pragma once

#include <string>

#include "image/image.h"

namespace mvtm {

// True when the file starts with a JPEG SOI marker and a marker (false for a missing file).
bool IsJpegFile(const std::string& path);

// Reads `path` into `img` (header only when `header_only`) and returns true, or returns false
// for a colour space this reader leaves to OpenImageIO. Throws Error(path, 0, ...).
bool ReadJpeg(const std::string& path, bool header_only, Image* img);

}  // namespace mvtm
