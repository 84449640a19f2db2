// mvtm — a headless OpenGL 3.3 core context.
//
// Backends, tried in this order by kAuto:
//   EGL, device platform (EGL_EXT_platform_device: a GPU, or Mesa's software device),
//   EGL, surfaceless platform (EGL_MESA_platform_surfaceless),
//   OSMesa (Mesa's off-screen renderer).
// EGL is loaded at run time through a glad loader generated at build time (libEGL.so.1); OSMesa is
// linked. No program links libGL. Rendering goes to framebuffer objects (no window, no pbuffer
// surface).
//
// Thread safety: one context per process at a time, current on the creating thread (glad's
// function pointers are global). A context can be created and destroyed repeatedly.
#pragma once

#include <memory>
#include <string>
#include <utility>
#include <vector>

namespace mvtm {

enum class GlBackend { kAuto, kEgl, kOsMesa };

// The backends and their names, for a declared choice option (run/option_table.h).
const std::vector<std::pair<GlBackend, std::string>>& GlBackendTable();

class GlContext {
 public:
  // Creates a GL 3.3 core context and loads the GL function pointers. Throws Error with the
  // reasons every backend failed.
  static std::unique_ptr<GlContext> Create(GlBackend backend = GlBackend::kAuto);
  virtual ~GlContext() = default;
  // "EGL device: llvmpipe (LLVM 15.0.6, 256 bits) / Mesa 22.3.6" and the like.
  virtual std::string Describe() const = 0;
};

}  // namespace mvtm
