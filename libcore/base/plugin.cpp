#include "base/plugin.h"

#include <dlfcn.h>

#include <cstdlib>
#include <filesystem>
#include <map>
#include <mutex>
#include <vector>

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

}  // namespace mvtm
