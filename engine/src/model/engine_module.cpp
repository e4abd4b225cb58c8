#include "model/engine_module.h"

#include <dlfcn.h>

#include <filesystem>
#include <system_error>

namespace rdmesh {

Result<const void*> LoadEngineModule(const std::string& file, const char* entry,
                                     const std::string& what, int version) {
  std::error_code error;
  std::filesystem::path self = std::filesystem::read_symlink("/proc/self/exe", error);
  const std::string module = (self.parent_path() / file).string();
  void* handle = error ? nullptr : dlopen(module.c_str(), RTLD_NOW | RTLD_LOCAL);
  if (handle == nullptr) {
    const char* why = dlerror();
    const std::string reason = error ? error.message() : why != nullptr ? why : "unknown";
    // The loader maps the module into the address space: under a memory limit (rdmesh batch
    // --memory-limit, a container's) that is where the memory runs out.
    if (reason.find("failed to map segment") != std::string::npos)
      return Status(StatusCode::kResourceExhausted,
                    "out of memory: cannot map " + what + " (" + module + ")");
    return Status(StatusCode::kInternal, "cannot load " + what + " (" + reason + ")");
  }
  using Entry = const void* (*)();
  auto function = reinterpret_cast<Entry>(dlsym(handle, entry));
  const void* api = function != nullptr ? function() : nullptr;
  if (api == nullptr || *static_cast<const int*>(api) != version)
    return Status(StatusCode::kInternal, "cannot load " + what + ": " + module +
                                             " is not the module of this build of rdmesh");
  return api;
}

}  // namespace rdmesh
