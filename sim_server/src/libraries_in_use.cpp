#include "libraries_in_use.hpp"

#include <dlfcn.h>

namespace skillbus::sim {

namespace {

// The path of the library the dynamic linker binds `symbol` to in this process.
std::string library_path_of(const char* symbol) {
  void* f = dlsym(RTLD_DEFAULT, symbol);
  Dl_info info{};
  if (f == nullptr || dladdr(f, &info) == 0 || info.dli_fname == nullptr) return "unknown";
  return info.dli_fname;
}

std::string library_of(const char* symbol) {
  const std::string file = library_path_of(symbol);
  return file.substr(file.find_last_of('/') + 1);
}

}  // namespace

std::string allocator_in_use() {
  // Asked of the running process, not of the build (a library found at build time but not
  // loaded, or another one preloaded by hand, shows here as it is). C++'s operator new is
  // bound on its own: preloading glibc alone puts its malloc first, not its operator new.
  const std::string c = library_of("malloc"), cxx = library_of("_Znwm");
  return c == cxx ? c : c + " (operator new: " + cxx + ")";
}

std::string dart_in_use() {
  // dart::simulation::World::step(bool): in libdart, not inlined into our code.
  return library_path_of("_ZN4dart10simulation5World4stepEb");
}

}  // namespace skillbus::sim
