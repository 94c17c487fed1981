#include "skillbus/apps/summary.hpp"

#include <cmath>
#include <cstdio>

namespace skillbus::apps {

void print_summary(const Summary& s) {
  const std::string line = s.dump(-1, ' ', false, nlohmann::ordered_json::error_handler_t::replace);
  std::printf("%s\n", line.c_str());
  std::fflush(stdout);
}

double rounded(double x, int decimals) {
  if (!std::isfinite(x)) return x;
  const double scale = std::pow(10.0, decimals);
  return std::round(x * scale) / scale;
}

}  // namespace skillbus::apps
