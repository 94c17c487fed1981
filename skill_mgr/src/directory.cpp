#include "directory.hpp"

namespace skillbus::skills {

std::string managers_probe_channel() { return channel("SB_MANAGERS_PROBE"); }
std::string managers_channel() { return channel("SB_MANAGERS"); }

Directory::Directory(Bus& bus, Describe describe) : bus_(bus), describe_(std::move(describe)) {
  subscription_ = bus_.subscribe(managers_probe_channel(), [this](const std::string&, const uint8_t*, size_t) { answer(); });
  answer();
}

void Directory::answer() {
  const auto now = std::chrono::steady_clock::now();
  if (now - window_ >= std::chrono::seconds(1)) {
    window_ = now;
    answered_in_window_ = 0;
  }
  if (++answered_in_window_ > 20) return;
  skillbus_msgs::skill_manager_info_t info = describe_();
  info.header.frame = -1;
  info.header.sender = info.name;
  publish_msg(bus_, managers_channel(), info);
}

}  // namespace skillbus::skills
