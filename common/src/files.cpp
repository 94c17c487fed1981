#include "skillbus/files.hpp"

#include <cctype>
#include <stdexcept>

namespace skillbus {

std::string file_in(const std::string& dir, const std::string& name, const std::string& suffix,
                    const std::string& what) {
  auto refuse = [&](const std::string& why) {
    std::string shown = name.substr(0, 100);
    for (char& c : shown)
      if (!std::isprint(static_cast<unsigned char>(c))) c = '?';
    throw std::invalid_argument(what + " '" + shown + "': " + why);
  };
  if (dir.empty()) refuse("this server has no directory for such files (send the content instead)");
  if (name.empty() || name.size() > 100) refuse("a name is 1 to 100 characters");
  if (name[0] == '.') refuse("a name, not a path: it may not start with '.'");
  for (char c : name)
    if (!(std::isalnum(static_cast<unsigned char>(c)) || c == '_' || c == '-' || c == '.'))
      refuse("a name, not a path: letters, digits, '_', '-' and '.' only");
  const bool has_suffix = name.size() >= suffix.size() && name.compare(name.size() - suffix.size(), suffix.size(), suffix) == 0;
  return dir + "/" + name + (has_suffix ? "" : suffix);
}

}  // namespace skillbus
