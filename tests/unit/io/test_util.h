#pragma once
#include <unistd.h>

#include <filesystem>
#include <fstream>
#include <string>

namespace mvtm::test {

inline std::filesystem::path FreshDir(const std::string& name) {
  auto d = std::filesystem::temp_directory_path() /
           ("mvtm-test-" + name + "-" + std::to_string(getpid()));
  std::filesystem::remove_all(d);
  std::filesystem::create_directories(d);
  return d;
}

inline void WriteFile(const std::filesystem::path& p, const std::string& s) {
  std::ofstream(p, std::ios::binary) << s;
}

inline std::string ReadFile(const std::filesystem::path& p) {
  std::ifstream f(p, std::ios::binary);
  return std::string(std::istreambuf_iterator<char>(f), {});
}

// Real data: MVTM_DATA, else the path configured at build time. Empty when absent.
inline std::string DataDir() {
  const char* e = std::getenv("MVTM_DATA");
  std::string d = e ? e : MVTM_DATA_DIR;
  return std::filesystem::is_directory(d) ? d : "";
}

}  // namespace mvtm::test
