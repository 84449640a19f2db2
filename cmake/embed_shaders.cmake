# Writes OUT (a .cpp) holding every file in SHADERS as a string, looked up by file name.
# Run at build time (add_custom_command), so editing a shader rebuilds the programs.
string(REPLACE "|" ";" SHADERS "${SHADERS}")
set(_body "")
foreach(f ${SHADERS})
  file(READ ${f} _src)
  get_filename_component(_name ${f} NAME)
  string(APPEND _body "  {\"${_name}\", R\"mvtm_glsl(${_src})mvtm_glsl\"},\n")
endforeach()
file(WRITE ${OUT}.tmp "// Generated from shaders/ by cmake/embed_shaders.cmake. Do not edit.\n#include <map>\n#include <string>\nnamespace mvtm {\nconst std::map<std::string, std::string>& EmbeddedShaders() {\n  static const std::map<std::string, std::string> s = {\n${_body}  };\n  return s;\n}\n}  // namespace mvtm\n")
file(RENAME ${OUT}.tmp ${OUT})
