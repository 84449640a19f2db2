// mvtm — plugin modules opened with dlopen on first use.
//
// Some libraries cost every program that links them tens or hundreds of milliseconds at
// start-up (OpenImageIO ~0.47 s and 260 libraries, OpenVDB ~50 ms) while only a few runs need
// them. Their code lives in modules of mvtm's own (libmvtm_oiio.so, libmvtm_vdb.so) that a
// program opens only when it needs one. Modules are looked for in $MVTM_PLUGIN_DIR, in
// lib/mvtm/ beside the program's bin/ folder (as built and as installed), then in the build and
// install folders mvtm was configured with.
#pragma once

#include <string>

namespace mvtm {

// Opens `module` (a file name such as "libmvtm_vdb.so") once per process and returns the
// address of its extern "C" function `entry`, or nullptr with *failure saying why (not found,
// with the folders tried; not loadable, with the loader's message). Thread-safe.
void* PluginEntry(const std::string& module, const std::string& entry, std::string* failure);

// A module's function table: `entry` is an extern "C" function returning a const Table* whose
// first member is `int abi`. Returns it when its abi is `abi`, else nullptr with *failure set.
// Callers keep the result in a function-local static (opened once per process).
template <class Table>
const Table* PluginTable(const std::string& module, const std::string& entry, int abi,
                         std::string* failure) {
  void* sym = PluginEntry(module, entry, failure);
  const Table* table = sym ? reinterpret_cast<const Table* (*)()>(sym)() : nullptr;
  if (sym && (!table || table->abi != abi)) {
    *failure = module + " is not this mvtm's module (ABI " + std::to_string(abi) + " expected)";
    return nullptr;
  }
  return table;
}

// The running program's identity: the checksums (base/file_stamp.h's FNV-1a) of its executable
// (/proc/self/exe: the tools link libcore and their shaders statically) and of every mvtm module
// (libmvtm_*.so) the folders above offer, the first of each name as PluginEntry would open it,
// folded into 16 hex digits; computed once per process (a few milliseconds). A change to any of
// mvtm's code changes it. Without /proc/self/exe, "version " + kVersion. Thread-safe.
const std::string& ProgramChecksum();

}  // namespace mvtm
