// OSMesa, kept in its own translation unit: <GL/osmesa.h> includes the system <GL/gl.h>,
// which must not meet glad's gl.h.
#pragma once

#include <string>

namespace mvtm::osmesa {

using ProcAddress = void (*)();
// Creates a 3.3 core context rendering into an internal 1×1 buffer (we draw into FBOs) and makes
// it current. Returns an opaque handle; throws Error.
void* CreateCurrent(std::string& description);
void Destroy(void* handle);
ProcAddress GetProcAddress(const char* name);

}  // namespace mvtm::osmesa
