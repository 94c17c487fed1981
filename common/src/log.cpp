#include "skillbus/log.hpp"

#include <algorithm>
#include <cctype>
#include <string>
#include <cstdio>
#include <cstdlib>
#include <cstring>

namespace skillbus {
namespace {

LogLevel initial_level() {
  const char* env = std::getenv("SKILLBUS_LOG_LEVEL");
  if (!env) return LogLevel::Info;
  std::string v;
  for (const char* c = env; *c; ++c)
    if (*c != ' ') v += static_cast<char>(std::tolower(static_cast<unsigned char>(*c)));
  if (v == "debug") return LogLevel::Debug;
  if (v == "info") return LogLevel::Info;
  if (v == "warn" || v == "warning") return LogLevel::Warn;
  if (v == "error") return LogLevel::Error;
  // (as the Python programs say it: a typo is not a silent info)
  std::fprintf(stderr, "warning: $SKILLBUS_LOG_LEVEL '%s' is not debug, info, warn or error: logging at info\n",
               log_safe(env, 64).c_str());
  return LogLevel::Info;
}

LogLevel g_level = initial_level();
const char* kNames[] = {"debug", "info", "warn", "error"};

}  // namespace

void set_log_level(LogLevel level) { g_level = level; }

std::string log_safe(const std::string& text, size_t max_bytes) {
  std::string out;
  out.reserve(std::min(text.size(), max_bytes) + 16);
  static const char kHex[] = "0123456789abcdef";
  for (size_t i = 0; i < text.size(); ++i) {
    if (out.size() >= max_bytes) {
      out += "... (" + std::to_string(text.size() - i) + " more bytes)";
      break;
    }
    const auto c = static_cast<unsigned char>(text[i]);
    if (c == '\\') {
      out += "\\\\";
    } else if (c < 0x20 || c == 0x7f) {  // a newline or a terminal escape would forge lines
      out += "\\x";
      out += kHex[c >> 4];
      out += kHex[c & 15];
    } else {
      out += static_cast<char>(c);
    }
  }
  return out;
}

void log_line(LogLevel level, const std::string& component, const std::string& text) {
  if (level < g_level) return;
  // Log text often quotes what came over the wire: one line per call, escaped, bounded.
  std::fprintf(stderr, "[%s] %s: %s\n", kNames[static_cast<int>(level)], log_safe(component, 200).c_str(),
               log_safe(text, 2000).c_str());
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
