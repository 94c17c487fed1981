// Tiny `--key value` / `--flag` parser for the command-line tools in apps/.
#pragma once

#include <csignal>
#include <cstdio>
#include <cstdlib>
#include <iostream>
#include <map>
#include <sstream>
#include <string>
#include <vector>

namespace skillbus::apps {

// The flag SIGTERM and SIGINT set once stop_on_signals() has been called: the servers'
// run loops end cleanly on it (and print their summary).
inline volatile std::sig_atomic_t& stop_requested() {
  static volatile std::sig_atomic_t flag = 0;
  return flag;
}
inline void stop_on_signals() {
  stop_requested();  // created before any handler can run
  auto handler = [](int) { stop_requested() = 1; };
  std::signal(SIGTERM, handler);
  std::signal(SIGINT, handler);
}

// Runs a server's start-up; what it throws is printed as "<program>: cannot start: why"
// and ends the process with exit code 2.
template <class F>
void start_or_exit(const char* program, F&& start) {
  try {
    start();
  } catch (const std::exception& e) {
    std::fprintf(stderr, "%s: cannot start: %s\n", program, e.what());
    std::exit(2);
  }
}

// A string as the inside of a JSON string literal (the tools' one-line summaries):
// quotes and backslashes escaped, control characters as spaces.
inline std::string json_escape(const std::string& s) {
  std::string o;
  for (char c : s) {
    if (c == '"' || c == '\\') o += '\\';
    if (static_cast<unsigned char>(c) < 0x20) {
      o += ' ';
      continue;
    }
    o += c;
  }
  return o;
}

class Args {
 public:
  // `flags` take no value; every other --key takes one. Unknown keys are an error.
  Args(int argc, char** argv, const std::vector<std::string>& keys, const std::vector<std::string>& flags = {}) {
    for (int i = 1; i < argc; ++i) {
      std::string a = argv[i];
      if (a.rfind("--", 0) != 0) die("unexpected argument '" + a + "'");
      a = a.substr(2);
      if (is_in(a, flags)) {
        values_[a] = "1";
      } else if (is_in(a, keys)) {
        if (i + 1 >= argc) die("--" + a + " needs a value");
        values_[a] = argv[++i];
      } else {
        die("unknown option --" + a);
      }
    }
  }
  std::string str(const std::string& k, const std::string& def = "") const {
    auto it = values_.find(k);
    return it == values_.end() ? def : it->second;
  }
  long long num(const std::string& k, long long def) const {
    auto it = values_.find(k);
    if (it == values_.end()) return def;
    char* end = nullptr;
    const long long v = std::strtoll(it->second.c_str(), &end, 10);
    if (!end || *end) die("--" + k + " wants an integer, got '" + it->second + "'");
    return v;
  }
  double real(const std::string& k, double def) const {
    auto it = values_.find(k);
    if (it == values_.end()) return def;
    char* end = nullptr;
    const double v = std::strtod(it->second.c_str(), &end);
    if (!end || *end) die("--" + k + " wants a number, got '" + it->second + "'");
    return v;
  }
  bool flag(const std::string& k) const { return values_.count(k) > 0; }
  std::vector<std::string> list(const std::string& k) const {
    std::vector<std::string> out;
    std::stringstream ss(str(k));
    for (std::string item; std::getline(ss, item, ',');)
      if (!item.empty()) out.push_back(item);
    return out;
  }
  [[noreturn]] static void die(const std::string& why) {
    std::cerr << "error: " << why << "\n";
    std::exit(2);
  }

 private:
  static bool is_in(const std::string& k, const std::vector<std::string>& v) {
    for (const auto& x : v)
      if (x == k) return true;
    return false;
  }
  std::map<std::string, std::string> values_;
};

}  // namespace skillbus::apps
