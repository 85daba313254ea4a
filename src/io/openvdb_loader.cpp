// Finds and loads the OpenVDB module (openvdb_module.h) the first time a .vdb is read or written.
#include <dlfcn.h>
#include <unistd.h>

#include <climits>
#include <cstdlib>
#include <mutex>
#include <string>
#include <vector>

#include "io/openvdb_module.h"

// Defined when the module's source is linked into the program itself (the fuzz target).
extern "C" __attribute__((weak)) const sdfcontour::detail::OpenVdbFunctions*
sdfcontour_openvdb_functions();

namespace sdfcontour::detail {

namespace {

constexpr const char* kModuleFile = "sdfcontour_openvdb.so";

// Where to look, first found wins: $SDFCONTOUR_OPENVDB_MODULE (a file), beside the running
// program (the build tree's CLI), where an installed program's module is (bin/../lib/sdfcontour),
// the build tree, the install tree.
std::vector<std::string> module_candidates() {
  std::vector<std::string> paths;
  if (const char* set = std::getenv("SDFCONTOUR_OPENVDB_MODULE"); set && *set) paths.push_back(set);
  char self[PATH_MAX];
  const ssize_t length = ::readlink("/proc/self/exe", self, sizeof(self) - 1);
  if (length > 0) {
    std::string dir(self, std::size_t(length));
    dir.erase(dir.find_last_of('/') + 1);
    paths.push_back(dir + kModuleFile);
    paths.push_back(dir + "../" + SDFCONTOUR_INSTALL_MODULE_RELATIVE_DIR + "/" + kModuleFile);
  }
  paths.push_back(std::string(SDFCONTOUR_BUILD_MODULE_DIR) + "/" + kModuleFile);
  paths.push_back(std::string(SDFCONTOUR_INSTALL_MODULE_DIR) + "/" + kModuleFile);
  return paths;
}

const OpenVdbFunctions* load() {
  if (sdfcontour_openvdb_functions) return sdfcontour_openvdb_functions();
  std::string tried;
  for (const std::string& path : module_candidates()) {
    if (::access(path.c_str(), R_OK) != 0) {
      tried += (tried.empty() ? "" : ", ") + path;
      continue;
    }
    // Kept loaded for the rest of the process: OpenVDB registers types globally.
    void* handle = ::dlopen(path.c_str(), RTLD_NOW | RTLD_LOCAL);
    if (!handle) {
      const char* why = ::dlerror();
      throw IoError("cannot load the OpenVDB module '" + path + "': " + (why ? why : "unknown"));
    }
    using Entry = const OpenVdbFunctions* (*)();
    auto entry = reinterpret_cast<Entry>(::dlsym(handle, "sdfcontour_openvdb_functions"));
    if (!entry) throw IoError("'" + path + "' is not sdfcontour's OpenVDB module");
    return entry();
  }
  throw IoError("sdfcontour's OpenVDB module (" + std::string(kModuleFile) +
                ") is not installed; looked for " + tried);
}

}  // namespace

const OpenVdbFunctions& openvdb_functions() {
  static std::once_flag once;
  static const OpenVdbFunctions* functions = nullptr;
  std::call_once(once, [] { functions = load(); });  // a throw leaves `once` unset: retried
  return *functions;
}

}  // namespace sdfcontour::detail
