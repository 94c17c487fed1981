#pragma once
// The code of a SPARQL query, for the server's checks of its words (SERVICE, VALUES'
// short form, property paths): a word inside a comment, a string or an IRI is no keyword.
#include <string>

namespace skillbus::wm::sparql_detail {

// `query` with each comment (# to the end of its line) made a line break, each string
// literal ('...', "...", '''...''', """...""") made "" and each IRI (<...>) made <>,
// following SPARQL 1.1's grammar; everything else as it is. A '<' that starts no IRI (a
// comparison) stays. An unterminated string or IRI ends the text: the parser refuses it.
std::string sparql_code(const std::string& query);

}  // namespace skillbus::wm::sparql_detail
