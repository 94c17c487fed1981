#include "skillbus/log.hpp"

#include <cstdio>
#include <cstdlib>
#include <cstring>

namespace skillbus {
namespace {

LogLevel initial_level() {
  const char* env = std::getenv("SKILLBUS_LOG_LEVEL");
  if (!env) return LogLevel::Info;
  if (!std::strcmp(env, "debug")) return LogLevel::Debug;
  if (!std::strcmp(env, "warn")) return LogLevel::Warn;
  if (!std::strcmp(env, "error")) return LogLevel::Error;
  return LogLevel::Info;
}

LogLevel g_level = initial_level();
const char* kNames[] = {"debug", "info", "warn", "error"};

}  // namespace

void set_log_level(LogLevel level) { g_level = level; }

void log_line(LogLevel level, const std::string& component, const std::string& text) {
  if (level < g_level) return;
  std::fprintf(stderr, "[%s] %s: %s\n", kNames[static_cast<int>(level)], component.c_str(), text.c_str());
  std::fflush(stderr);
}

void BadInputCounter::record(const std::string& channel, const std::string& why, size_t size) {
  const long n = ++by_channel_[channel];
  ++total_;
  if (n <= 5 || n % 1000 == 0)
    SB_WARN(component_, "bad message #" << n << " on " << channel << " (" << size << " bytes): " << why
                                        << " -- dropped");
}

std::string BadInputCounter::summary() const {
  if (by_channel_.empty()) return "none";
  std::string s;
  for (const auto& [ch, n] : by_channel_) s += (s.empty() ? "" : " ") + ch + "=" + std::to_string(n);
  return s;
}

}  // namespace skillbus
