// The world's graph for SPARQL, parsed once per world version and indexed, served to Rasqal
// as its triples source (internal to sparql.cpp).
//
// Why: Rasqal's own triples source parses the data graph again for every query and keeps
// it as a list that every triple pattern scans from the start, so a join of two patterns
// over 10,000 elements scanned the graph once per binding of the first (seconds a query).
// This one keeps Rasqal's terms and its RDF term equality (a candidate is confirmed with
// Rasqal's own comparison, exactly as its source does) and only narrows the candidates
// by the pattern's bound subject, object or predicate.
#pragma once

#include <rasqal.h>

#include <string>
#include <unordered_map>
#include <vector>

namespace skillbus::wm::sparql_detail {

class IndexedGraph {
 public:
  // The triples of `turtle` (one graph) as Rasqal terms of `world`; throws WmError when
  // the text does not parse (Raptor's message goes to the world's log handler).
  IndexedGraph(rasqal_world* world, const std::string& turtle);
  ~IndexedGraph();
  IndexedGraph(const IndexedGraph&) = delete;
  IndexedGraph& operator=(const IndexedGraph&) = delete;

  size_t size() const { return triples_.size(); }
  const rasqal_triple* at(uint32_t i) const { return triples_[i]; }

  // The positions that can match a pattern whose bound parts are `s`, `p`, `o` (nullptr
  // where unbound): a superset of the matches, never missing one; `all` is set instead
  // when no bound part narrows them.
  const std::vector<uint32_t>* candidates(rasqal_literal* s, rasqal_literal* p, rasqal_literal* o, bool& all) const;

 private:
  struct Parsing;  // Raptor's callbacks while the graph is read (sparql_graph.cpp)
  // What a term is found by in the indexes: an IRI by its raptor_uri (Raptor interns IRIs,
  // checked when a graph is read), a blank node by this graph's term for it; a literal is
  // not indexed (a pattern bound to one is narrowed by its other parts, and every
  // candidate is confirmed by Rasqal's comparison).
  struct Key {
    enum Kind { kIndexed, kLiteral, kAbsent } kind;  // (kAbsent: a blank node not in the graph)
    const void* id;
  };
  Key key_of(const rasqal_literal* l) const;
  rasqal_literal* term(raptor_term* t);
  void add(rasqal_literal* s, rasqal_literal* p, rasqal_literal* o);
  void free_terms();

  using Index = std::unordered_map<const void*, std::vector<uint32_t>>;
  rasqal_world* world_;
  std::vector<rasqal_triple*> triples_;
  Index by_subject_, by_predicate_, by_object_;
  std::unordered_map<const raptor_uri*, rasqal_literal*> iris_;  // one Rasqal term per IRI ...
  std::unordered_map<std::string, rasqal_literal*> blanks_;      // ... and per blank node
  int anonymous_ = 0;    // blank nodes without a label, numbered as read
  bool failed_ = false;  // a term or triple that could not be made, or a callback that threw
};

// Makes `world` answer every query from `*graph` (the graph current when the query runs;
// nullptr: an empty graph). Call after rasqal_world_open.
void serve_from(rasqal_world* world, const IndexedGraph* const* graph);

}  // namespace skillbus::wm::sparql_detail
