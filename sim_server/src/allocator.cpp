#include "allocator.hpp"

#include <dlfcn.h>

namespace skillbus::sim {

std::string allocator_in_use() {
  // Asked of the running process, not of the build: the `malloc` the dynamic linker binds
  // calls to, and the file it comes from (a library found at build time but not loaded, or
  // another one preloaded by hand, shows here as it is).
  void* m = dlsym(RTLD_DEFAULT, "malloc");
  Dl_info info{};
  if (m == nullptr || dladdr(m, &info) == 0 || info.dli_fname == nullptr) return "unknown";
  const std::string file = info.dli_fname;
  return file.substr(file.find_last_of('/') + 1);
}

}  // namespace skillbus::sim
