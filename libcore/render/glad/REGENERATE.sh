#!/bin/sh
# The committed GL 3.3 core + EGL 1.5 loader was generated with Debian bookworm's glad 2.0.2
# (package python3-glad) from its bundled Khronos XML (--reproducible: nothing is downloaded):
cd "$(dirname "$0")" && rm -rf include src && glad --quiet --reproducible \
  --api gl:core=3.3,egl=1.5 \
  --extensions EGL_EXT_platform_base,EGL_EXT_platform_device,EGL_EXT_device_base,EGL_EXT_device_enumeration,EGL_EXT_device_query,EGL_MESA_platform_surfaceless,EGL_KHR_no_config_context,EGL_KHR_surfaceless_context,GL_KHR_debug \
  --out-path . c --loader
