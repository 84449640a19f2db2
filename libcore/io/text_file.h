// mvtm — opening a text input file for the stream readers of libcore/io.
//
// Every reader of libcore/io has a stream version ReadX(std::istream&, name) and a path version
// that opens the file with OpenTextFile and calls it, so both report "PATH:LINE: what" alike.
#pragma once

#include <fstream>
#include <string>

#include "base/error.h"

namespace mvtm {

// Opens `path` (binary mode: CR is stripped by the readers, not by the stream); throws
// Error("PATH: cannot open") like LineReader(path).
inline std::ifstream OpenTextFile(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  if (!in) throw Error(path, 0, "cannot open");
  return in;
}

}  // namespace mvtm
