#include "render/gl_program.h"

#include <glad/gl.h>

#include <map>
#include <sstream>

#include "base/error.h"

namespace mvtm {

const std::map<std::string, std::string>& EmbeddedShaders();  // generated (embed_shaders.cmake)

const std::string& ShaderSource(const std::string& name) {
  const auto& all = EmbeddedShaders();
  auto it = all.find(name);
  if (it == all.end()) throw Error("no embedded shader '" + name + "'");
  return it->second;
}

namespace {

std::string Variant(const std::vector<std::string>& defines) {
  std::string v;
  for (const auto& d : defines) v += (v.empty() ? "" : " ") + d;
  return "[" + v + "]";
}

// Maps GLSL "S:L(C): msg" or "S(L) : msg" locations back to file names via the #line source
// numbers we assigned (1 = first file, …).
std::string Relocate(const std::string& log, const std::vector<std::string>& files,
                     const std::string& variant) {
  std::istringstream in(log);
  std::string line, out;
  while (std::getline(in, line)) {
    if (line.empty()) continue;
    // Mesa: "SOURCE:LINE(COLUMN): message"
    size_t colon = line.find(':'), paren = line.find('('), close = line.find("):");
    bool mesa = colon != std::string::npos && paren != std::string::npos &&
                close != std::string::npos && colon > 0 && colon < paren && paren < close &&
                line.find_first_not_of("0123456789") == colon &&
                line.find_first_not_of("0123456789", colon + 1) == paren;
    if (mesa) {
      size_t src = std::stoul(line.substr(0, colon));
      std::string file = src >= 1 && src <= files.size() ? files[src - 1] : "?";
      std::string msg = line.substr(close + 2);
      size_t b = msg.find_first_not_of(' ');
      return "shaders/" + file + ":" + line.substr(colon + 1, paren - colon - 1) + " " + variant +
             ": " + (b == std::string::npos ? "" : msg.substr(b));
    }
    if (out.empty()) out = line;
  }
  return files.back() + " " + variant + ": " + (out.empty() ? "compile failed" : out);
}

// A source file: its name (for messages) and its text.
struct Source {
  std::string name, text;
};

unsigned Compile(GLenum type, const std::vector<Source>& files,
                 const std::vector<std::string>& defines) {
  std::string src = "#version 330 core\n";
  for (const auto& d : defines) src += "#define " + d + "\n";
  std::vector<std::string> names;
  for (size_t i = 0; i < files.size(); ++i) {
    src += "#line 1 " + std::to_string(i + 1) + "\n" + files[i].text + "\n";
    names.push_back(files[i].name);
  }
  GLuint s = glCreateShader(type);
  const char* p = src.c_str();
  glShaderSource(s, 1, &p, nullptr);
  glCompileShader(s);
  GLint ok = 0;
  glGetShaderiv(s, GL_COMPILE_STATUS, &ok);
  if (!ok) {
    GLint len = 0;
    glGetShaderiv(s, GL_INFO_LOG_LENGTH, &len);
    std::string log(static_cast<size_t>(std::max(len, 1)), '\0');
    glGetShaderInfoLog(s, len, nullptr, log.data());
    glDeleteShader(s);
    throw Error(Relocate(log, names, Variant(defines)));
  }
  return s;
}

unsigned Link(const std::vector<Source>& vertex, const std::vector<Source>& fragment,
              const std::vector<std::string>& defines) {
  GLuint vs = Compile(GL_VERTEX_SHADER, vertex, defines);
  GLuint fs;
  try {
    fs = Compile(GL_FRAGMENT_SHADER, fragment, defines);
  } catch (...) {
    glDeleteShader(vs);
    throw;
  }
  GLuint prog = glCreateProgram();
  glAttachShader(prog, vs);
  glAttachShader(prog, fs);
  glLinkProgram(prog);
  glDeleteShader(vs);
  glDeleteShader(fs);
  GLint ok = 0;
  glGetProgramiv(prog, GL_LINK_STATUS, &ok);
  if (!ok) {
    char log[2048] = {0};
    glGetProgramInfoLog(prog, sizeof log, nullptr, log);
    glDeleteProgram(prog);
    throw Error("shaders/" + vertex.back().name + " + " + fragment.back().name + " " +
                Variant(defines) + ": link failed: " + log);
  }
  return prog;
}

}  // namespace

unsigned BuildProgram(const std::string& vertex, const std::string& fragment,
                      const std::vector<std::string>& defines,
                      const std::vector<std::string>& fragment_includes) {
  std::vector<Source> ff;
  for (const auto& f : fragment_includes) ff.push_back({f, ShaderSource(f)});
  ff.push_back({fragment, ShaderSource(fragment)});
  return Link({{vertex, ShaderSource(vertex)}}, ff, defines);
}

unsigned BuildProgramFromText(const std::string& name, const std::string& vertex_text,
                              const std::string& fragment_text) {
  return Link({{name + ".vert", vertex_text}}, {{name + ".frag", fragment_text}}, {});
}

}  // namespace mvtm
