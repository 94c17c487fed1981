#pragma once
// Which malloc the process runs on, for its report (sim_server links tcmalloc when it can;
// sim_server/CMakeLists.txt).
#include <string>

namespace skillbus::sim {

// The file name of the library whose `malloc` (and C++ operator new) this process calls:
// "libtcmalloc_minimal.so.4" when tcmalloc is in use; when the two differ, both, as
// "libc.so.6 (operator new: libstdc++.so.6)" (glibc's malloc, and libstdc++'s operator new,
// which calls it).
std::string allocator_in_use();

}  // namespace skillbus::sim
