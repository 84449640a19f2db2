// mvtm — GLSL programs built from the embedded shaders/ files with #define variants.
#pragma once

#include <string>
#include <vector>

namespace mvtm {

// Compiles and links vertex + fragment shaders from the embedded files (shaders/NAME), each
// prefixed with "#version 330 core", the `defines` ("MVTM_PTM", "MVTM_MAX_PROJECTORS 4", …) and
// the `includes` (shared files such as ptm_common.glsl). A compile error throws Error naming the
// file, the variant and the line: "shaders/ptm.frag:12 [MVTM_PTM MVTM_MASKS]: error: ...".
// Requires a current context. Returns the program id.
unsigned BuildProgram(const std::string& vertex, const std::string& fragment,
                      const std::vector<std::string>& defines,
                      const std::vector<std::string>& fragment_includes);

// The same for shaders made at run time (benchmarks, experiments): the texts without the
// #version line, named NAME.vert and NAME.frag in messages.
unsigned BuildProgramFromText(const std::string& name, const std::string& vertex_text,
                              const std::string& fragment_text);

// The source text of an embedded shader; throws Error when there is none of that name.
const std::string& ShaderSource(const std::string& name);

}  // namespace mvtm
