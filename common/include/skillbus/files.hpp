// Files a server opens on a request's behalf: only by name, inside one directory of its
// own. A request that names a path ("../journal.bin", "/etc/shadow") is refused before any
// file is touched, so a request can neither overwrite the server's data nor learn whether
// a file exists elsewhere or what it begins with.
#pragma once

#include <string>

namespace skillbus {

// DIR/NAME (NAME + suffix when it does not end in it). NAME: letters, digits, '_', '-'
// and '.', not starting with '.', at most 100 characters. Throws std::invalid_argument
// saying so (and naming `what`, e.g. "scene name") otherwise, or when `dir` is empty.
std::string file_in(const std::string& dir, const std::string& name, const std::string& suffix,
                    const std::string& what);

}  // namespace skillbus
