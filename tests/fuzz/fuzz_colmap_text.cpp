// mvtm — libFuzzer harness: COLMAP text model files (cameras.txt, images.txt, points3D.txt stream
// readers). The same input goes to each of the three readers and to the in-order images.txt reader.
// Accepts only mvtm::Error; see fuzz_util.h.
#include <sstream>

#include "base/error.h"
#include "fuzz_util.h"
#include "io/colmap_model.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  const std::string text = mvtm::fuzz::AsString(data, size);
  try {
    std::istringstream in(text);
    mvtm::ReadColmapCamerasText(in, "cameras.txt");
  } catch (const mvtm::Error&) {
  }
  try {
    std::istringstream in(text);
    mvtm::ReadColmapImagesText(in, "images.txt");
  } catch (const mvtm::Error&) {
  }
  try {
    std::istringstream in(text);
    mvtm::ReadColmapPoints3DText(in, "points3D.txt");
  } catch (const mvtm::Error&) {
  }
  try {
    std::istringstream in(text);
    size_t n = 0;
    mvtm::ForEachColmapImageText(in, "images.txt", [&](mvtm::ImageRecord&&, long) { ++n; });
  } catch (const mvtm::Error&) {
  }
  return 0;
}
