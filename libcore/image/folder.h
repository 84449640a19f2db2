// mvtm — the image files of a folder, the one way every tool lists them.
//
// Regular files whose extension (any case) is an image format the image layer reads, not
// hidden (no leading '.'), not in sub-folders, sorted by file name (byte order) — the order in
// which tools number frames. Throws Error naming the folder when it cannot be read.
#pragma once

#include <filesystem>
#include <string>
#include <vector>

namespace mvtm {

// The extensions (lower case, with the dot) that count as images.
const std::vector<std::string>& ImageExtensions();

// File names (not paths) of the images in `dir`. With `only` non-empty, just those extensions
// (lower case, with the dot: {".png"} for label images, which must be lossless).
std::vector<std::string> ListImageFiles(const std::filesystem::path& dir,
                                        const std::vector<std::string>& only = {});

}  // namespace mvtm
