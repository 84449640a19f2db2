#include "render/context.h"

#include <glad/egl.h>
#include <glad/gl.h>

#include <vector>

#include "base/error.h"
#include "render/osmesa_backend.h"

namespace mvtm {

const std::vector<std::pair<GlBackend, std::string>>& GlBackendTable() {
  static const std::vector<std::pair<GlBackend, std::string>> table = {
      {GlBackend::kAuto, "auto"}, {GlBackend::kEgl, "egl"}, {GlBackend::kOsMesa, "osmesa"}};
  return table;
}

namespace {

std::string GlDescription() {
  auto str = [](GLenum e) {
    const GLubyte* s = glGetString(e);
    return s ? std::string(reinterpret_cast<const char*>(s)) : std::string("?");
  };
  return str(GL_RENDERER) + " / " + str(GL_VERSION);
}

void CheckGl33(const std::string& who) {
  GLint major = 0, minor = 0;
  glGetIntegerv(GL_MAJOR_VERSION, &major);
  glGetIntegerv(GL_MINOR_VERSION, &minor);
  if (major * 10 + minor < 33)
    throw Error(who + ": GL " + std::to_string(major) + "." + std::to_string(minor) + " < 3.3");
}

class EglContext : public GlContext {
 public:
  EglContext(EGLDisplay display, EGLContext context, std::string what)
      : display_(display), context_(context), what_(std::move(what)) {}
  ~EglContext() override {
    eglMakeCurrent(display_, EGL_NO_SURFACE, EGL_NO_SURFACE, EGL_NO_CONTEXT);
    eglDestroyContext(display_, context_);
    eglTerminate(display_);
  }
  std::string Describe() const override { return what_; }

 private:
  EGLDisplay display_;
  EGLContext context_;
  std::string what_;
};

class OsMesaContext : public GlContext {
 public:
  OsMesaContext(void* handle, std::string what) : handle_(handle), what_(std::move(what)) {}
  ~OsMesaContext() override { osmesa::Destroy(handle_); }
  std::string Describe() const override { return what_; }

 private:
  void* handle_;
  std::string what_;
};

GLADapiproc EglProc(const char* name) {
  return reinterpret_cast<GLADapiproc>(eglGetProcAddress(name));
}
GLADapiproc OsMesaProc(const char* name) {
  return reinterpret_cast<GLADapiproc>(osmesa::GetProcAddress(name));
}

// Initialises `display`, creates a 3.3 core context current without a surface. Empty on failure
// (with the reason in `why`).
std::unique_ptr<GlContext> TryEglDisplay(EGLDisplay display, const std::string& platform,
                                         std::string& why) {
  if (display == EGL_NO_DISPLAY) {
    why += platform + ": no display; ";
    return nullptr;
  }
  EGLint major = 0, minor = 0;
  if (!eglInitialize(display, &major, &minor)) {
    why += platform + ": eglInitialize failed; ";
    return nullptr;
  }
  gladLoaderLoadEGL(display);  // now with the display's extensions
  if (!eglBindAPI(EGL_OPENGL_API)) {
    eglTerminate(display);
    why += platform + ": no desktop OpenGL; ";
    return nullptr;
  }
  const EGLint config_attribs[] = {EGL_SURFACE_TYPE,
                                   EGL_PBUFFER_BIT,
                                   EGL_RENDERABLE_TYPE,
                                   EGL_OPENGL_BIT,
                                   EGL_RED_SIZE,
                                   8,
                                   EGL_GREEN_SIZE,
                                   8,
                                   EGL_BLUE_SIZE,
                                   8,
                                   EGL_NONE};
  EGLConfig config = nullptr;
  EGLint n = 0;
  if (!eglChooseConfig(display, config_attribs, &config, 1, &n) || n < 1) config = nullptr;
  const EGLint ctx_attribs[] = {EGL_CONTEXT_MAJOR_VERSION,
                                3,
                                EGL_CONTEXT_MINOR_VERSION,
                                3,
                                EGL_CONTEXT_OPENGL_PROFILE_MASK,
                                EGL_CONTEXT_OPENGL_CORE_PROFILE_BIT,
                                EGL_NONE};
  EGLContext ctx =
      eglCreateContext(display, config ? config : EGL_NO_CONFIG_KHR, EGL_NO_CONTEXT, ctx_attribs);
  if (ctx == EGL_NO_CONTEXT) {
    eglTerminate(display);
    why += platform + ": no GL 3.3 core context; ";
    return nullptr;
  }
  if (!eglMakeCurrent(display, EGL_NO_SURFACE, EGL_NO_SURFACE, ctx)) {
    eglDestroyContext(display, ctx);
    eglTerminate(display);
    why += platform + ": cannot make current without a surface; ";
    return nullptr;
  }
  if (!gladLoadGL(EglProc)) {
    eglMakeCurrent(display, EGL_NO_SURFACE, EGL_NO_SURFACE, EGL_NO_CONTEXT);
    eglDestroyContext(display, ctx);
    eglTerminate(display);
    why += platform + ": cannot load GL functions; ";
    return nullptr;
  }
  auto c = std::make_unique<EglContext>(display, ctx, "EGL " + platform + ": " + GlDescription());
  CheckGl33("EGL");
  return c;
}

std::unique_ptr<GlContext> TryEgl(std::string& why) {
  if (!gladLoaderLoadEGL(EGL_NO_DISPLAY)) {
    why += "EGL: libEGL.so.1 not found; ";
    return nullptr;
  }
  if (GLAD_EGL_EXT_platform_device && GLAD_EGL_EXT_device_enumeration) {
    EGLDeviceEXT devices[16];
    EGLint n = 0;
    if (eglQueryDevicesEXT(16, devices, &n))
      for (EGLint i = 0; i < n; ++i) {
        EGLDisplay d = eglGetPlatformDisplayEXT(EGL_PLATFORM_DEVICE_EXT, devices[i], nullptr);
        if (auto c = TryEglDisplay(d, "device " + std::to_string(i), why)) return c;
      }
  }
  if (GLAD_EGL_MESA_platform_surfaceless) {
    EGLDisplay d =
        eglGetPlatformDisplayEXT(EGL_PLATFORM_SURFACELESS_MESA, EGL_DEFAULT_DISPLAY, nullptr);
    if (auto c = TryEglDisplay(d, "surfaceless", why)) return c;
  }
  return nullptr;
}

}  // namespace

std::unique_ptr<GlContext> GlContext::Create(GlBackend backend) {
  std::string why;
  if (backend != GlBackend::kOsMesa) {
    if (auto c = TryEgl(why)) return c;
  }
  if (backend != GlBackend::kEgl) {
    try {
      std::string what;
      void* h = osmesa::CreateCurrent(what);
      if (!gladLoadGL(OsMesaProc)) {
        osmesa::Destroy(h);
        throw Error("OSMesa: cannot load GL functions");
      }
      auto c = std::make_unique<OsMesaContext>(h, what + ": " + GlDescription());
      CheckGl33("OSMesa");
      return c;
    } catch (const Error& e) {
      why += std::string(e.what()) + "; ";
    }
  }
  if (why.size() >= 2) why.resize(why.size() - 2);
  throw Error("no headless OpenGL 3.3 context: " + why);
}

}  // namespace mvtm
