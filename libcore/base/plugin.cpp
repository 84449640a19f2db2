#include "base/plugin.h"

#include <dlfcn.h>

#include <algorithm>
#include <cstdlib>
#include <filesystem>
#include <map>
#include <mutex>
#include <set>
#include <vector>

#include "base/error.h"
#include "base/file_stamp.h"
#include "base/version.h"

#ifndef MVTM_PLUGIN_BUILD_DIR
#define MVTM_PLUGIN_BUILD_DIR ""
#endif
#ifndef MVTM_PLUGIN_INSTALL_DIR
#define MVTM_PLUGIN_INSTALL_DIR ""
#endif

namespace mvtm {

namespace {

std::vector<std::filesystem::path> PluginDirs() {
  std::vector<std::filesystem::path> dirs;
  if (const char* env = std::getenv("MVTM_PLUGIN_DIR"); env && *env) dirs.emplace_back(env);
  std::error_code ec;
  const auto exe = std::filesystem::read_symlink("/proc/self/exe", ec);
  if (!ec) dirs.push_back(exe.parent_path().parent_path() / "lib" / "mvtm");
  for (const char* d : {MVTM_PLUGIN_BUILD_DIR, MVTM_PLUGIN_INSTALL_DIR})
    if (*d) dirs.emplace_back(d);
  return dirs;
}

struct Opened {
  void* handle = nullptr;
  std::string failure;
};

}  // namespace

void* PluginEntry(const std::string& module, const std::string& entry, std::string* failure) {
  static std::mutex mutex;
  static std::map<std::string, Opened> opened;  // modules stay loaded for the process's life
  std::lock_guard<std::mutex> lock(mutex);
  auto [it, fresh] = opened.try_emplace(module);
  Opened& o = it->second;
  if (fresh) {
    std::string tried;
    for (const auto& dir : PluginDirs()) {
      const auto candidate = dir / module;
      std::error_code ec;
      if (!std::filesystem::is_regular_file(candidate, ec)) {
        tried += (tried.empty() ? "" : ", ") + dir.string();
        continue;
      }
      o.handle = dlopen(candidate.c_str(), RTLD_NOW | RTLD_LOCAL);
      if (!o.handle) {
        const char* why = dlerror();
        o.failure = why ? why : "dlopen failed";
      }
      break;
    }
    if (!o.handle && o.failure.empty())
      o.failure = "mvtm's module " + module + " is not installed (looked in " + tried + ")";
  }
  if (!o.handle) {
    *failure = o.failure;
    return nullptr;
  }
  void* sym = dlsym(o.handle, entry.c_str());
  if (!sym) *failure = module + " has no " + entry + " (not this mvtm's module?)";
  return sym;
}

const std::string& ProgramChecksum() {
  static const std::string checksum = [] {
    std::string id;
    try {
      id = "exe " + FileChecksum("/proc/self/exe");
    } catch (const Error&) {
      return std::string("version ") + kVersion;
    }
    std::set<std::string> names;  // the first module of each name, as PluginEntry opens it
    for (const auto& dir : PluginDirs()) {
      std::error_code ec;
      std::vector<std::filesystem::path> files;
      for (const auto& e : std::filesystem::directory_iterator(dir, ec)) files.push_back(e.path());
      std::sort(files.begin(), files.end());
      for (const auto& f : files) {
        const std::string name = f.filename().string();
        if (name.rfind("libmvtm_", 0) != 0 || f.extension() != ".so" || !names.insert(name).second)
          continue;
        try {
          id += "\n" + name + " " + FileChecksum(f);
        } catch (const Error&) {
          id += "\n" + name + " unreadable";
        }
      }
    }
    return Hex64(Fnv1a64(id.data(), id.size()));
  }();
  return checksum;
}

}  // namespace mvtm
