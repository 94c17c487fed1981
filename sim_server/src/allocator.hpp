#pragma once
// Which malloc the process runs on, for its report (sim_server links tcmalloc when it can;
// sim_server/CMakeLists.txt).
#include <string>

namespace skillbus::sim {

// The file name of the library whose `malloc` this process calls: "libtcmalloc_minimal.so.4"
// when tcmalloc is in use, "libc.so.6" for glibc's, whatever LD_PRELOAD put first otherwise.
std::string allocator_in_use();

}  // namespace skillbus::sim
