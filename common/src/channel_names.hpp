// A channel's name ending, by which the transports class channels (LCM's lane of acks and
// joins, DDS's requests and state). Internal to skillbus_common.
#pragma once

#include <string>
#include <string_view>

namespace skillbus::detail {

inline bool ends_with(const std::string& s, std::string_view tail) {
  return s.size() >= tail.size() && s.compare(s.size() - tail.size(), tail.size(), tail) == 0;
}

}  // namespace skillbus::detail
