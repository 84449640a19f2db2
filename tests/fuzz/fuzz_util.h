// mvtm — helpers shared by the libFuzzer harnesses in tests/fuzz/.
//
// Every harness defines LLVMFuzzerTestOneInput, feeds the input to one parser and catches only
// mvtm::Error (UsageError derives from it): any other exception (std::bad_alloc,
// std::out_of_range, a library's own exception type) escapes and is reported as a crash, since
// a reader must turn every malformed input into a one-line "FILE:LINE: what" Error.
// Built with -DMVTM_FUZZ=ON (clang) they are libFuzzer binaries; otherwise replay_main.cpp runs
// them over the committed corpora as ctests.
#pragma once

#include <stdlib.h>
#include <unistd.h>

#include <cstddef>
#include <cstdint>
#include <cstdio>
#include <filesystem>
#include <stdexcept>
#include <string>

namespace mvtm::fuzz {

inline std::string AsString(const uint8_t* data, size_t size) {
  return std::string(reinterpret_cast<const char*>(data), size);
}

// /dev/shm when it exists (no disk traffic), else /tmp.
inline std::string TempRoot() {
  return std::filesystem::is_directory("/dev/shm") ? "/dev/shm" : "/tmp";
}

inline void WriteAll(int fd, const uint8_t* data, size_t size) {
  while (size > 0) {
    ssize_t n = ::write(fd, data, size);
    if (n <= 0) throw std::runtime_error("fuzz: cannot write a temporary file");
    data += n;
    size -= static_cast<size_t>(n);
  }
}

// A new file holding the bytes, named TEMP/mvtm-fuzz-XXXXXX<suffix>; removed on destruction.
class TempFile {
 public:
  TempFile(const uint8_t* data, size_t size, const std::string& suffix) {
    std::string templ = TempRoot() + "/mvtm-fuzz-XXXXXX" + suffix;
    int fd = ::mkstemps(templ.data(), static_cast<int>(suffix.size()));
    if (fd < 0) throw std::runtime_error("fuzz: mkstemps failed");
    path_ = templ;
    WriteAll(fd, data, size);
    ::close(fd);
  }
  ~TempFile() { ::unlink(path_.c_str()); }
  TempFile(const TempFile&) = delete;
  TempFile& operator=(const TempFile&) = delete;
  const std::string& path() const { return path_; }

 private:
  std::string path_;
};

// A new empty folder TEMP/mvtm-fuzz-XXXXXX; removed with its contents on destruction.
class TempDir {
 public:
  TempDir() {
    std::string templ = TempRoot() + "/mvtm-fuzz-XXXXXX";
    if (!::mkdtemp(templ.data())) throw std::runtime_error("fuzz: mkdtemp failed");
    path_ = templ;
  }
  ~TempDir() {
    std::error_code ec;
    std::filesystem::remove_all(path_, ec);
  }
  TempDir(const TempDir&) = delete;
  TempDir& operator=(const TempDir&) = delete;
  const std::string& path() const { return path_; }
  // Writes DIR/name holding the bytes.
  std::string Add(const std::string& name, const uint8_t* data, size_t size) const {
    std::string p = path_ + "/" + name;
    FILE* f = std::fopen(p.c_str(), "wb");
    if (!f) throw std::runtime_error("fuzz: cannot create " + p);
    if (size > 0 && std::fwrite(data, 1, size, f) != size) {
      std::fclose(f);
      throw std::runtime_error("fuzz: cannot write " + p);
    }
    std::fclose(f);
    return p;
  }

 private:
  std::string path_;
};

}  // namespace mvtm::fuzz
