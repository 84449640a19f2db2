#include "image/mask.h"

namespace mvtm {

Image MaskFromImage(const Image& img) {
  Image m(img.width, img.height, 1, 8, 0.f);
  const size_t c = static_cast<size_t>(img.channels);
  for (size_t p = 0; p < img.pixels(); ++p)
    for (size_t k = 0; k < c; ++k)
      if (img.data[p * c + k] != 0) {
        m.data[p] = 255.f;
        break;
      }
  return m;
}

Image ReadMask(const std::string& path) { return MaskFromImage(ReadImage(path)); }

size_t CountSet(const Image& mask) {
  size_t n = 0;
  for (float v : mask.data) n += v != 0;
  return n;
}

}  // namespace mvtm
