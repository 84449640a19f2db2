#include "image/folder.h"

#include <algorithm>
#include <cctype>
#include <system_error>

#include "base/error.h"

namespace mvtm {

namespace fs = std::filesystem;

const std::vector<std::string>& ImageExtensions() {
  static const std::vector<std::string> exts = {".png", ".jpg", ".jpeg", ".tif", ".tiff", ".exr",
                                                ".pgm", ".ppm", ".pnm",  ".bmp", ".hdr",  ".webp"};
  return exts;
}

std::vector<std::string> ListImageFiles(const fs::path& dir, const std::vector<std::string>& only) {
  const std::vector<std::string>& accept = only.empty() ? ImageExtensions() : only;
  std::error_code ec;
  fs::directory_iterator it(dir, ec);
  if (ec) throw Error(dir.string(), 0, "cannot list the folder: " + ec.message());
  std::vector<std::string> names;
  for (const auto& e : it) {
    const std::string name = e.path().filename().string();
    if (name.empty() || name[0] == '.' || !e.is_regular_file(ec)) continue;
    std::string ext = e.path().extension().string();
    std::transform(ext.begin(), ext.end(), ext.begin(),
                   [](unsigned char c) { return char(std::tolower(c)); });
    if (std::find(accept.begin(), accept.end(), ext) != accept.end()) names.push_back(name);
  }
  std::sort(names.begin(), names.end());
  return names;
}

}  // namespace mvtm
