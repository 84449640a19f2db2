#include "render/osmesa_backend.h"

#include <GL/osmesa.h>

#include <vector>

#include "base/error.h"

namespace mvtm::osmesa {

namespace {
struct Handle {
  OSMesaContext ctx = nullptr;
  std::vector<unsigned char> buffer;
};
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
  auto* h = new Handle;
  h->ctx = OSMesaCreateContextAttribs(attribs, nullptr);
  if (!h->ctx) {
    delete h;
    throw Error("OSMesa: cannot create a GL 3.3 core context");
  }
  h->buffer.resize(4 * 16 * 16);
  if (!OSMesaMakeCurrent(h->ctx, h->buffer.data(), GL_UNSIGNED_BYTE, 16, 16)) {
    OSMesaDestroyContext(h->ctx);
    delete h;
    throw Error("OSMesa: cannot make the context current");
  }
  description = "OSMesa";
  return h;
}

void Destroy(void* handle) {
  auto* h = static_cast<Handle*>(handle);
  if (!h) return;
  OSMesaMakeCurrent(nullptr, nullptr, 0, 0, 0);
  OSMesaDestroyContext(h->ctx);
  delete h;
}

ProcAddress GetProcAddress(const char* name) {
  return reinterpret_cast<ProcAddress>(OSMesaGetProcAddress(name));
}

}  // namespace mvtm::osmesa
