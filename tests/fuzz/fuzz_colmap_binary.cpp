// mvtm — libFuzzer harness: COLMAP binary model (cameras.bin, images.bin, points3D.bin) through
// ReadColmapBinary(dir). Input: byte 0 picks the layout; 0, 1, 2: the rest is cameras.bin,
// images.bin or points3D.bin and the other two files hold an empty list (count 0); 3: the rest
// is split into the three files by two little-endian uint16 lengths (cameras, images) that
// follow byte 0, points3D.bin taking what remains.
// Accepts only mvtm::Error; see fuzz_util.h.
#include <algorithm>

#include "base/error.h"
#include "fuzz_util.h"
#include "io/colmap_model.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  if (size < 1) return 0;
  static const uint8_t kEmpty[8] = {0, 0, 0, 0, 0, 0, 0, 0};
  const char* names[3] = {"cameras.bin", "images.bin", "points3D.bin"};
  const uint8_t* part[3] = {kEmpty, kEmpty, kEmpty};
  size_t len[3] = {8, 8, 8};
  const int mode = data[0] % 4;
  ++data;
  --size;
  if (mode < 3) {
    part[mode] = data;
    len[mode] = size;
  } else {
    if (size < 4) return 0;
    size_t a = std::min<size_t>(data[0] | (data[1] << 8), size - 4);
    size_t b = std::min<size_t>(data[2] | (data[3] << 8), size - 4 - a);
    part[0] = data + 4;
    len[0] = a;
    part[1] = data + 4 + a;
    len[1] = b;
    part[2] = data + 4 + a + b;
    len[2] = size - 4 - a - b;
  }
  mvtm::fuzz::TempDir dir;
  for (int i = 0; i < 3; ++i) dir.Add(names[i], part[i], len[i]);
  try {
    mvtm::ReadColmapBinary(dir.path());
  } catch (const mvtm::Error&) {
  }
  return 0;
}
