#include "common/image/image_formats_loader.h"

#include <dlfcn.h>
#include <fmt/format.h>

#include <filesystem>
#include <mutex>
#include <stdexcept>
#include <string>

#include "common/image/image_formats_module.h"

namespace portico {

void* imageFormatsEntry(const char* name) {
  static std::once_flag once;
  static void* handle = nullptr;
  static std::string module, failure;
  std::call_once(once, [] {
    // Every program lands in bin/, beside the module.
    std::error_code error;
    const auto program = std::filesystem::read_symlink("/proc/self/exe", error);
    module = (program.parent_path() / kImageFormatsModule).string();
    handle = dlopen(module.c_str(), RTLD_NOW | RTLD_LOCAL);
    if (!handle) failure = fmt::format("cannot load {} ({})", module, dlerror());
  });
  if (!handle) throw std::runtime_error(failure);
  void* entry = dlsym(handle, name);
  if (!entry) throw std::runtime_error(fmt::format("{} has no {}", module, name));
  return entry;
}

}  // namespace portico
