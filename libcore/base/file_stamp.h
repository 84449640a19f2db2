// mvtm — what identifies a file's content: cheaply (size and modification time, one stat) and
// surely (a 64-bit FNV-1a checksum of its bytes). Outputs' staleness (run/ledger.h) and
// provenance records use both: the stat first, the checksum only when the time changed.
#pragma once

#include <cstddef>
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

// 64-bit FNV-1a (offset basis 14695981039346656037, prime 1099511628211) of `size` bytes,
// continuing from `h` (pass a previous result to hash data in pieces).
inline constexpr uint64_t kFnv1aOffset = 1469598103934665603ULL;
uint64_t Fnv1a64(const void* data, size_t size, uint64_t h = kFnv1aOffset);
// A 64-bit hash as 16 lowercase hex digits.
std::string Hex64(uint64_t h);

// 64-bit FNV-1a of a file's bytes, as 16 hex digits. Throws Error when unreadable.
std::string FileChecksum(const fs::path& path);

}  // namespace mvtm
