// mvtm — the interface of libmvtm_oiio.so, mvtm's OpenImageIO plugin.
//
// Linking Debian's libOpenImageIO costs every program about 0.47 s at start-up (it loads some
// 260 shared libraries). mvtm reads and writes the pipeline's formats (PNG, JPEG, float EXR)
// through their own libraries and opens this plugin with dlopen only when a file needs another
// format (TIFF, BMP, WebP, CMYK JPEG, multi-part EXR, ...), so no program links OpenImageIO.
// The plugin is built with mvtm and installed beside it (lib/mvtm/); MVTM_PLUGIN_DIR overrides
// where it is looked for.
//
// The functions never throw: they return "" on success or a one-line message (without the
// path), so no exception crosses the library boundary.
#pragma once

#include <string>
#include <vector>

#include "image/image.h"

namespace mvtm {

inline constexpr int kOiioPluginAbi = 1;

struct OiioPlugin {
  int abi = kOiioPluginAbi;
  // Reads `path` into `img` (width, height, channels, bits only when `header_only`).
  std::string (*read)(const std::string& path, bool header_only, Image* img);
  // Encodes `img` in the format of `path`'s extension. Formats that can encode in memory fill
  // `bytes` and write nothing; the others write the file `file_target` and leave `bytes` empty.
  std::string (*write)(const std::string& path, const Image& img, const std::string& file_target,
                       std::vector<unsigned char>* bytes);
};

}  // namespace mvtm

// The one symbol the plugin exports.
extern "C" const mvtm::OiioPlugin* mvtm_oiio_plugin();
