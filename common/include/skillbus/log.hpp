// Minimal logging to stderr: "[level] component: message". Log lines are for people;
// nothing in behaviour depends on them (they may read the wall clock).
#pragma once

#include <map>
#include <sstream>
#include <string>

namespace skillbus {

enum class LogLevel { Debug = 0, Info = 1, Warn = 2, Error = 3 };

void log_line(LogLevel level, const std::string& component, const std::string& text);
// `text` as one printable line: control characters and backslashes escaped (\xNN, \\),
// cut after `max_bytes` with a note of how much was left out. log_line applies it.
std::string log_safe(const std::string& text, size_t max_bytes = 2000);
void set_log_level(LogLevel level);  // default Info, or $SKILLBUS_LOG_LEVEL (debug, info, warn, error, any case; another value is said on stderr)

// Counts bad input per channel and logs the first few of each channel, then every
// 1000th, so that a flood of garbage cannot flood the log.
class BadInputCounter {
 public:
  explicit BadInputCounter(std::string component) : component_(std::move(component)) {}
  void record(const std::string& channel, const std::string& why, size_t size);
  long total() const { return total_; }
  const std::map<std::string, long>& by_channel() const { return by_channel_; }
  std::string summary() const;  // "SB_X=3 SB_Y=1" or "none"

 private:
  std::string component_;
  std::map<std::string, long> by_channel_;
  long total_ = 0;
};

}  // namespace skillbus

#define SB_LOG(level, component, expr)                              \
  do {                                                              \
    std::ostringstream sb_log_os_;                                  \
    sb_log_os_ << expr;                                             \
    ::skillbus::log_line(level, component, sb_log_os_.str());       \
  } while (0)
#define SB_INFO(c, e) SB_LOG(::skillbus::LogLevel::Info, c, e)
#define SB_WARN(c, e) SB_LOG(::skillbus::LogLevel::Warn, c, e)
#define SB_ERROR(c, e) SB_LOG(::skillbus::LogLevel::Error, c, e)
#define SB_DEBUG(c, e) SB_LOG(::skillbus::LogLevel::Debug, c, e)
