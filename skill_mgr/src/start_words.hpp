// The words of a --start task ("Type[:label] KEY=VALUE ..."): split at blanks, except
// inside double quotes, which are dropped (Goal="(skiros:contain a b), (skiros:contain a c)"
// is one word). Throws std::runtime_error for a quote left open.
#pragma once

#include <string>
#include <vector>

namespace skillbus::skills {

std::vector<std::string> split_start_words(const std::string& text);

}  // namespace skillbus::skills
