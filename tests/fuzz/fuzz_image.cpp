// mvtm — libFuzzer harness: images through the image layer (image/image.h ReadImageSpec, then
// ReadImage). Byte 0 picks the extension of the temporary file (0: .png, 1: .exr, 2: .jpg, by value
// mod 3); the rest is the file. Accepts only mvtm::Error; see fuzz_util.h.
// Slow (~10 inputs/s): ReadImage allocates and zero-fills the pixels a fuzzed header claims.
#include "base/error.h"
#include "fuzz_util.h"
#include "image/image.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  if (size < 1) return 0;
  static const char* const kExt[3] = {".png", ".exr", ".jpg"};
  mvtm::fuzz::TempFile file(data + 1, size - 1, kExt[data[0] % 3]);
  try {
    mvtm::ReadImageSpec(file.path());
  } catch (const mvtm::Error&) {
  }
  try {
    mvtm::ReadImage(file.path());
  } catch (const mvtm::Error&) {
  }
  return 0;
}
