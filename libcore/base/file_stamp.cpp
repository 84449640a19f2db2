#include "base/file_stamp.h"

#include <sys/stat.h>

#include <cstdio>
#include <fstream>

#include "base/error.h"

namespace mvtm {

FileStamp StatFile(const fs::path& path) {
  FileStamp s;
  struct stat st {};
  if (::stat(path.c_str(), &st) != 0 || !S_ISREG(st.st_mode)) return s;
  s.exists = true;
  s.bytes = static_cast<uint64_t>(st.st_size);
  s.mtime_ns = static_cast<int64_t>(st.st_mtim.tv_sec) * 1000000000 + st.st_mtim.tv_nsec;
  return s;
}

uint64_t Fnv1a64(const void* data, size_t size, uint64_t h) {
  const auto* p = static_cast<const unsigned char*>(data);
  for (size_t i = 0; i < size; ++i) {
    h ^= p[i];
    h *= 1099511628211ULL;
  }
  return h;
}

std::string Hex64(uint64_t h) {
  char hex[17];
  std::snprintf(hex, sizeof hex, "%016llx", static_cast<unsigned long long>(h));
  return hex;
}

std::string FileChecksum(const fs::path& path) {
  std::ifstream f(path, std::ios::binary);
  if (!f) throw Error(path.string(), 0, "cannot open");
  uint64_t h = kFnv1aOffset;
  char buf[1 << 16];
  while (f) {
    f.read(buf, sizeof buf);
    h = Fnv1a64(buf, static_cast<size_t>(f.gcount()), h);
  }
  return Hex64(h);
}

}  // namespace mvtm
