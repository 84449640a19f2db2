#include "render/osmesa_backend.h"

#include <GL/osmesa.h>
#include <dlfcn.h>

#include <mutex>
#include <vector>

#include "base/error.h"

namespace mvtm::osmesa {

namespace {
struct Handle {
  OSMesaContext ctx = nullptr;
  std::vector<unsigned char> buffer;
};

// libOSMesa is opened on first use, not linked: it loads LLVM (llvmpipe), which would add some
// 30 ms to the start of every program that links the renderer, --help and --version included.
struct Api {
  decltype(&OSMesaCreateContextAttribs) create = nullptr;
  decltype(&OSMesaMakeCurrent) make_current = nullptr;
  decltype(&OSMesaDestroyContext) destroy = nullptr;
  decltype(&OSMesaGetProcAddress) get_proc = nullptr;
};

const Api& Load() {
  static std::once_flag once;
  static Api api;
  static std::string failure;
  std::call_once(once, [] {
    void* lib = nullptr;
    for (const char* name : {"libOSMesa.so.8", "libOSMesa.so"})
      if ((lib = dlopen(name, RTLD_NOW | RTLD_LOCAL))) break;
    if (!lib) {
      failure =
          std::string("OSMesa: cannot load libOSMesa (Debian package libosmesa6): ") + dlerror();
      return;
    }
    Api a;
    a.create = reinterpret_cast<decltype(a.create)>(dlsym(lib, "OSMesaCreateContextAttribs"));
    a.make_current = reinterpret_cast<decltype(a.make_current)>(dlsym(lib, "OSMesaMakeCurrent"));
    a.destroy = reinterpret_cast<decltype(a.destroy)>(dlsym(lib, "OSMesaDestroyContext"));
    a.get_proc = reinterpret_cast<decltype(a.get_proc)>(dlsym(lib, "OSMesaGetProcAddress"));
    if (!a.create || !a.make_current || !a.destroy || !a.get_proc) {
      failure = "OSMesa: libOSMesa lacks OSMesaCreateContextAttribs (Mesa 11.2 or later needed)";
      return;
    }
    api = a;  // the library stays loaded for the life of the process
  });
  if (!api.create) throw Error(failure);
  return api;
}
}  // namespace

void* CreateCurrent(std::string& description) {
  const int attribs[] = {OSMESA_FORMAT,
                         OSMESA_RGBA,
                         OSMESA_DEPTH_BITS,
                         24,
                         OSMESA_PROFILE,
                         OSMESA_CORE_PROFILE,
                         OSMESA_CONTEXT_MAJOR_VERSION,
                         3,
                         OSMESA_CONTEXT_MINOR_VERSION,
                         3,
                         0};
  const Api& gl = Load();
  auto* h = new Handle;
  h->ctx = gl.create(attribs, nullptr);
  if (!h->ctx) {
    delete h;
    throw Error("OSMesa: cannot create a GL 3.3 core context");
  }
  h->buffer.resize(4 * 16 * 16);
  if (!gl.make_current(h->ctx, h->buffer.data(), GL_UNSIGNED_BYTE, 16, 16)) {
    gl.destroy(h->ctx);
    delete h;
    throw Error("OSMesa: cannot make the context current");
  }
  description = "OSMesa";
  return h;
}

void Destroy(void* handle) {
  auto* h = static_cast<Handle*>(handle);
  if (!h) return;
  const Api& gl = Load();
  gl.make_current(nullptr, nullptr, 0, 0, 0);
  gl.destroy(h->ctx);
  delete h;
}

ProcAddress GetProcAddress(const char* name) {
  return reinterpret_cast<ProcAddress>(Load().get_proc(name));
}

}  // namespace mvtm::osmesa
