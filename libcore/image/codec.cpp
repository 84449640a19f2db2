#include "image/codec.h"

#include <cstring>
#include <filesystem>

#include "base/error.h"
#include "image/image.h"

namespace mvtm {

void CheckImageDims(const std::string& path, int64_t width, int64_t height, int64_t channels) {
  if (width <= 0 || height <= 0 || channels <= 0) throw Error(path, 0, "image has no pixels");
  if (width > kMaxReadImageSide || height > kMaxReadImageSide || channels > 16 ||
      uint64_t(width) * uint64_t(height) > kMaxImagePixels)
    throw Error(path, 0,
                "image claims " + std::to_string(width) + "x" + std::to_string(height) + "x" +
                    std::to_string(channels) +
                    ", beyond mvtm's limits (65536 pixels a side, 2^30 pixels, 16 channels)");
}

void CheckHeaderFitsFile(const std::string& path, int64_t width, int64_t height, double raw,
                         double max_per_byte, double slack) {
  std::error_code ec;
  const auto size = std::filesystem::file_size(path, ec);
  if (!ec && raw > max_per_byte * double(size) + slack)
    throw Error(path, 0,
                "cannot read image: the file (" + std::to_string(size) +
                    " bytes) is too small for its " + std::to_string(width) + "x" +
                    std::to_string(height) + " header (truncated?)");
}

std::string LibraryText(std::string s) {
  for (char& c : s)
    if (c == '\n' || c == '\r') c = ' ';
  while (!s.empty() && s.back() == ' ') s.pop_back();
  for (const char* prefix : {"OpenEXR exception: ", "Iex::BaseExc: "})
    if (s.rfind(prefix, 0) == 0) s = "corrupt or truncated file: " + s.substr(std::strlen(prefix));
  return s.empty() ? "unknown error" : s;
}

}  // namespace mvtm
