#include "sparql_text.hpp"

#include <cstring>

namespace skillbus::wm::sparql_detail {

namespace {

// SPARQL 1.1 IRIREF: '<' ([^<>"{}|^`\] - [#x00-#x20])* '>'. The index of its '>', or npos
// when the '<' at `at` starts none (it is then a comparison: ?a < ?b, ?a <= 3).
size_t iri_end(const std::string& q, size_t at) {
  for (size_t i = at + 1; i < q.size(); ++i) {
    const unsigned char c = static_cast<unsigned char>(q[i]);
    if (c == '>') return i;
    if (c <= 0x20 || std::strchr("<\"{}|^`\\", c) != nullptr) return std::string::npos;
  }
  return std::string::npos;
}

// The index just past the string literal that starts at `at` (its quote), or the text's
// size when it does not end.
size_t string_end(const std::string& q, size_t at) {
  const char quote = q[at];
  const bool long_form = q.compare(at, 3, std::string(3, quote)) == 0;
  size_t i = at + (long_form ? 3 : 1);
  while (i < q.size()) {
    if (q[i] == '\\') {
      i += 2;  // (an escape: the next character is the string's)
    } else if (long_form ? q.compare(i, 3, std::string(3, quote)) == 0 : q[i] == quote) {
      return i + (long_form ? 3 : 1);
    } else {
      ++i;
    }
  }
  return q.size();
}

}  // namespace

std::string sparql_code(const std::string& query) {
  std::string out;
  out.reserve(query.size());
  size_t i = 0;
  while (i < query.size()) {
    const char c = query[i];
    if (c == '#') {
      const size_t eol = query.find_first_of("\r\n", i);
      out += '\n';
      i = eol == std::string::npos ? query.size() : eol + 1;
    } else if (c == '"' || c == '\'') {
      out += "\"\"";
      i = string_end(query, i);
    } else if (c == '<') {
      const size_t end = iri_end(query, i);
      if (end == std::string::npos) {
        out += c;
        ++i;
      } else {
        out += "<>";
        i = end + 1;
      }
    } else {
      out += c;
      ++i;
    }
  }
  return out;
}

}  // namespace skillbus::wm::sparql_detail
