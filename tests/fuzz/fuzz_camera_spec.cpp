// mvtm — libFuzzer harness: orb2colmap's --camera "MODEL W H PARAMS..." (camera/camera.h
// ParseCameraSpec); a parsed camera must project and unproject a point. Accepts only mvtm::Error;
// see fuzz_util.h.
#include "base/error.h"
#include "camera/camera.h"
#include "fuzz_util.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  try {
    const mvtm::Camera c = mvtm::ParseCameraSpec(mvtm::fuzz::AsString(data, size));
    c.Project(Eigen::Vector3d(0.1, -0.2, 2.0));
    c.Unproject(Eigen::Vector2d(1.0, 2.0), 3.0);
    c.Scaled(c.width / 2 + 1, c.height / 2 + 1);
  } catch (const mvtm::Error&) {
  }
  return 0;
}
