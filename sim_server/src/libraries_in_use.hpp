#pragma once
// Which libraries the running process took its allocator and its DART from, for its report
// (sim_server links tcmalloc when it can, sim_server/CMakeLists.txt; it loads DART built
// without assertions when the build made one, cmake/DartWithoutAssertions.cmake).
#include <string>

namespace skillbus::sim {

// The file name of the library whose `malloc` (and C++ operator new) this process calls:
// "libtcmalloc_minimal.so.4" when tcmalloc is in use; when the two differ, both, as
// "libc.so.6 (operator new: libstdc++.so.6)" (glibc's malloc, and libstdc++'s operator new,
// which calls it).
std::string allocator_in_use();

// The path of the libdart this process steps its world with, as the dynamic linker found it:
// the build's copy without assertions, or Debian's (/usr/lib/...).
std::string dart_in_use();

}  // namespace skillbus::sim
