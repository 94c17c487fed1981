// Channel names: the shared ones and each robot's own (skillbus/bus.hpp, channel()).
#include <cctype>
#include <cstdlib>
#include <mutex>
#include <stdexcept>

#include "skillbus/bus.hpp"

namespace skillbus {

namespace {

std::mutex robot_mutex;
std::string robot_set;  // by set_robot()
bool robot_was_set = false;

bool starts_with(const std::string& s, const char* prefix) { return s.rfind(prefix, 0) == 0; }

}  // namespace

bool robot_scoped(const std::string& name) {
  // The managers' discovery channel is shared: it is how a client finds every robot.
  if (name == "SB_SKILL_MANAGERS") return false;
  for (const char* p : {"SB_ROBOT_", "SB_SKILL_", "SB_SKPROC_", "SB_SKTREE_", "SB_MOTION_", "SB_CAN_"})
    if (starts_with(name, p)) return true;
  return name == "SB_SIM_STATE" || name == "SB_SIM_GRIPPER_CMD" || name == "SB_SIM_CMD_REPLY" || name == "SB_SIM_ATTACH";
}

// LCM's channel names end at 63 bytes: NAME/ and the longest robot channel must fit
// (skillbus.channels.MAX_ROBOT_NAME is the same).
constexpr size_t kMaxRobotName = 24;

bool valid_robot_name(const std::string& robot) {
  // (LCM's channel names end at 63 bytes: NAME/ and the longest robot channel must fit)
  if (robot.empty() || robot.size() > kMaxRobotName || !std::isalpha(static_cast<unsigned char>(robot[0])))
    return false;
  for (char c : robot)
    if (!std::isalnum(static_cast<unsigned char>(c)) && c != '_') return false;
  return true;
}

void set_robot(const std::string& robot) {
  if (!robot.empty() && !valid_robot_name(robot))
    throw std::invalid_argument("robot name '" + robot +
                                "': a letter, then letters, digits or _, at most " + std::to_string(kMaxRobotName) +
                                " (it becomes part of channel names)");
  std::lock_guard<std::mutex> lock(robot_mutex);
  robot_set = robot;
  robot_was_set = true;
}

std::string current_robot() {
  {
    std::lock_guard<std::mutex> lock(robot_mutex);
    if (robot_was_set) return robot_set;
  }
  const char* env = std::getenv("SKILLBUS_ROBOT");
  return env ? env : "";
}

std::string channel_too_long(const std::string& name) {
  if (name.size() <= kMaxChannel) return "";
  return "channel name '" + name + "' is " + std::to_string(name.size()) + " bytes: LCM ends channel names at " +
         std::to_string(kMaxChannel);
}

void refuse_long_channel(const std::string& name) {
  if (name.size() > kMaxChannel) throw BusError(channel_too_long(name));
}

void refuse_oversized(const std::string& channel, size_t size) {
  if (size > kMaxMessageBytes)
    throw BusError("a message of " + std::to_string(size) + " bytes on " + channel + ": over the " +
                   std::to_string(kMaxMessageBytes) + " bytes (16 MiB) a receiver reassembles, so every receiver "
                   "would drop it; send it in parts");
}

std::string channel_bad_characters(const std::string& name) {
  // What Cyclone DDS 0.10 takes in a topic name; LCM takes anything: one name, both transports.
  const auto ok = [](char c) { return std::isalnum(static_cast<unsigned char>(c)) && !(c & 0x80); };
  std::string bad;
  for (char c : name)
    if (!ok(c) && c != '_' && c != '/' && bad.find(c) == std::string::npos) bad += c;
  if (!bad.empty())
    return "channel name '" + name + "': '" + bad +
           "' cannot be in a channel name (letters, digits, _ and /: DDS topics allow no more)";
  if (name.empty() || std::isdigit(static_cast<unsigned char>(name[0])))
    return "channel name '" + name + "': a channel name cannot start with a digit (letters, digits, _ and /: DDS "
           "topics allow no more)";
  return "";
}

std::string robot_channel(const std::string& name, const std::string& robot) {
  const char* ns_env = std::getenv("SKILLBUS_NAMESPACE");
  const std::string ns = ns_env ? ns_env : "";
  const std::string mine = !robot.empty() && robot_scoped(name) ? robot : "";
  const std::string out = ns + (mine.empty() ? "" : mine + "/") + name;
  const std::string bad = channel_bad_characters(out);
  if (!bad.empty())
    throw std::invalid_argument(
        bad + (!ns.empty() && !channel_bad_characters(ns + "X").empty() ? " ($SKILLBUS_NAMESPACE is '" + ns + "')" : ""));
  const std::string why = channel_too_long(out);
  if (!why.empty()) {
    // Said where the name is made: later, on LCM, it subscribes and never hears a message.
    std::string parts;
    if (!ns.empty()) parts += "$SKILLBUS_NAMESPACE '" + ns + "' takes " + std::to_string(ns.size()) + ", ";
    if (!mine.empty()) parts += "robot " + mine + " takes " + std::to_string(mine.size() + 1) + ", ";
    parts += name + " takes " + std::to_string(name.size());
    throw std::invalid_argument(why + " (" + parts + "): shorten the name it is made of");
  }
  return out;
}

std::string channel(const std::string& name) { return robot_channel(name, current_robot()); }

}  // namespace skillbus
