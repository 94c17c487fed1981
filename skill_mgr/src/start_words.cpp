#include "start_words.hpp"

#include <cctype>
#include <stdexcept>

namespace skillbus::skills {

std::vector<std::string> split_start_words(const std::string& text) {
  std::vector<std::string> out;
  std::string word;
  bool quoted = false, have = false;  // `have`: a word has begun (an empty "" is a word)
  for (const char c : text) {
    if (c == '"') {
      quoted = !quoted;
      have = true;
    } else if (!quoted && std::isspace(static_cast<unsigned char>(c))) {
      if (have) out.push_back(word);
      word.clear();
      have = false;
    } else {
      word += c;
      have = true;
    }
  }
  if (quoted) throw std::runtime_error("--start: a '\"' is not closed in: " + text);
  if (have) out.push_back(word);
  return out;
}

}  // namespace skillbus::skills
