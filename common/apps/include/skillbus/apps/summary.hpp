// The one-line JSON summary every program prints on stdout when it ends (tests and the
// demo read the last JSON line of a program's output). Keys keep the order they are set in.
#pragma once

#include <nlohmann/json.hpp>

namespace skillbus::apps {

using Summary = nlohmann::ordered_json;

// Prints `s` as one line and flushes stdout. Text that is not valid UTF-8 is replaced,
// never an error.
void print_summary(const Summary& s);

// `x` rounded to `decimals` places: the precision a summary reports a measurement with.
double rounded(double x, int decimals);

}  // namespace skillbus::apps
