// mvtm — libFuzzer harness: PLY meshes through ReadMesh (io/mesh_io.h; ASCII and binary, float and
// double positions), from a temporary .ply file. Accepts only mvtm::Error; see fuzz_util.h.
#include "base/error.h"
#include "fuzz_util.h"
#include "io/mesh_io.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  mvtm::fuzz::TempFile file(data, size, ".ply");
  try {
    mvtm::ReadMesh(file.path());
  } catch (const mvtm::Error&) {
  }
  return 0;
}
