// SPARQL queries on the world model, answered by Rasqal (librasqal3): SELECT, ASK,
// CONSTRUCT and DESCRIBE over one graph given as Turtle (the server gives its ontology,
// the loaded scene's other triples and the world's elements). The world model's prefixes
// are declared for the query. Nothing else is read: FROM, FROM NAMED and SERVICE are
// refused.
#pragma once

#include <string>

#include "skillbus/wm/rdf.hpp"

namespace skillbus::wm {

// The results as SPARQL 1.1 Query Results JSON. Throws WmError naming the problem (the
// parser's message and line), or results larger than `max_bytes` (naming LIMIT/OFFSET).
std::string sparql_json(const std::string& query, const std::string& data_turtle, const Prefixes& prefixes,
                        size_t max_bytes);

}  // namespace skillbus::wm
