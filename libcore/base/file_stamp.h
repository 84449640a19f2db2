// mvtm — what identifies a file's content: cheaply (size and modification time, one stat) and
// surely (a 64-bit FNV-1a checksum of its bytes). Outputs' staleness (run/ledger.h) and
// provenance records use both: the stat first, the checksum only when the time changed.
#pragma once

#include <cstdint>
#include <filesystem>
#include <string>

namespace mvtm {

namespace fs = std::filesystem;

struct FileStamp {
  bool exists = false;  // a regular file (following symlinks)
  uint64_t bytes = 0;
  int64_t mtime_ns = 0;  // modification time, nanoseconds since the epoch
  std::string fnv1a64;   // empty until computed
};

// The size and modification time of `path`; exists = false when it is not a regular file.
FileStamp StatFile(const fs::path& path);

// 64-bit FNV-1a of a file's bytes, as 16 hex digits. Throws Error when unreadable.
std::string FileChecksum(const fs::path& path);

}  // namespace mvtm
