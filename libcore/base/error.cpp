#include "base/error.h"

namespace mvtm {

std::string Located(const std::string& file, long line, const std::string& what) {
  if (file.empty()) return what;
  if (line <= 0) return file + ": " + what;
  return file + ":" + std::to_string(line) + ": " + what;
}

Error::Error(const std::string& what) : std::runtime_error(what) {}

Error::Error(const std::string& file, long line, const std::string& what)
    : std::runtime_error(Located(file, line, what)), file_(file), line_(line) {}

}  // namespace mvtm
