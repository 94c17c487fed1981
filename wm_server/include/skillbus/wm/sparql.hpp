// SPARQL queries on the world model, answered by Rasqal (librasqal3): SELECT, ASK and
// CONSTRUCT (its triples as rows of subject, predicate and object) over one graph (the
// server gives its ontology, the loaded scene's other triples and the world's elements);
// DESCRIBE is refused (Rasqal does not implement it). The world model's prefixes
// are declared for the query. Nothing else is read: FROM, FROM NAMED and SERVICE are
// refused.
#pragma once

#include <cstdint>
#include <functional>
#include <memory>
#include <string>
#include <vector>

#include "skillbus/wm/rdf.hpp"

namespace skillbus::wm {

// Answers queries on a graph that it takes once per version of the world: the graph's
// triples are kept, indexed by subject, predicate and object, as Rasqal's triples source
// (Rasqal's own reads the data again for every query and scans it for every pattern).
// One thread at a time.
class SparqlEngine {
 public:
  SparqlEngine();
  ~SparqlEngine();
  SparqlEngine(const SparqlEngine&) = delete;
  SparqlEngine& operator=(const SparqlEngine&) = delete;

  // The results as SPARQL 1.1 Query Results JSON. `graph` is called for the graph's
  // triples only when `version` differs from the graph's (or none was read yet); its terms
  // become Rasqal's as Raptor would read them from the triples written as Turtle (a
  // relative IRI resolved against the world's base). Throws WmError naming the problem
  // (the parser's message and line), results larger than `max_bytes` (naming
  // LIMIT/OFFSET; never held larger than that), or a query that looked at more than
  // `max_examined` candidate triples (stopped there: one pattern that shares no variable
  // with the others makes a query as large as the graph's size to a power, which would
  // take the server's memory and time first), or, with ORDER BY or DISTINCT, more than
  // kMaxExaminedSorted. A count, not a clock: deterministic.
  std::string query_json(const std::string& query, int64_t version, const std::function<std::vector<Triple>()>& graph,
                         const Prefixes& prefixes, size_t max_bytes, uint64_t max_examined = kMaxExamined);

  // The default work bound: about half a second of matching here (3 s for 10 million
  // triples, a three-pattern cross join of the demo's world counted), and room for a query
  // that scans all of a 100,000-element world's types once or twice.
  static constexpr uint64_t kMaxExamined = 2'000'000;
  // The bound for a query with ORDER BY or DISTINCT (at most `max_examined`): Rasqal's
  // sort takes time that grows with the square of its rows (2.7 s for 10,000 here, 0.7 s for 5,000).
  static constexpr uint64_t kMaxExaminedSorted = 5'000;

  // How many times a graph was read (each new version once).
  int64_t graphs_read() const;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace skillbus::wm
