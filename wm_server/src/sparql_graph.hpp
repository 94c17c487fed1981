// The world's graph for SPARQL, made once per world version and indexed, served to Rasqal
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

#include <cstdint>
#include <string>
#include <unordered_map>
#include <vector>

#include "skillbus/wm/rdf.hpp"

namespace skillbus::wm::sparql_detail {

class IndexedGraph {
 public:
  // `triples` (one graph) as Rasqal terms of `world`, each as Raptor reads it from the
  // triples written as Turtle: an IRI resolved against the world's base (a relative one
  // becomes absolute), a blank node named "graphid0_<label>" (as Rasqal's own source names
  // the data's, apart from those a query makes), a literal with its datatype or language.
  // Throws WmError when a term cannot be made.
  IndexedGraph(rasqal_world* world, const std::vector<Triple>& triples);
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
  // What a term is found by in the indexes: an IRI by its raptor_uri (Raptor interns IRIs,
  // checked when a graph is read), a blank node by this graph's term for it; a literal is
  // not indexed (a pattern bound to one is narrowed by its other parts, and every
  // candidate is confirmed by Rasqal's comparison).
  struct Key {
    enum Kind { kIndexed, kLiteral, kAbsent } kind = kLiteral;  // (kAbsent: a blank node not in the graph)
    const void* id = nullptr;
  };
  Key key_of(const rasqal_literal* l) const;
  rasqal_literal* term(const Term& t);
  void add(rasqal_literal* s, rasqal_literal* p, rasqal_literal* o);
  void free_terms();

  using Index = std::unordered_map<const void*, std::vector<uint32_t>>;
  rasqal_world* world_;
  std::vector<rasqal_triple*> triples_;
  Index by_subject_, by_predicate_, by_object_;
  std::unordered_map<const raptor_uri*, rasqal_literal*> iris_;  // one Rasqal term per IRI ...
  std::unordered_map<std::string, rasqal_literal*> blanks_;      // ... and per blank node
  std::unordered_map<std::string, rasqal_literal*> iri_texts_;   // the term of each IRI text met
  raptor_uri* base_ = nullptr;                                   // what relative IRIs resolve against
};

// What the triples source serves, and whether a pattern could not be matched while a query
// ran (out of memory: Rasqal then ends the query's rows quietly, so the engine asks this).
//
// And how much work the query has done: every candidate triple a pattern looks at counts,
// and past `budget` every pattern ends, the query with `over_budget`. A count, not a
// clock: the same query on the same world fails the same way on any machine (lockstep).
struct Served {
  const IndexedGraph* graph = nullptr;  // nullptr: an empty graph
  bool failed = false;
  uint64_t examined = 0;
  uint64_t budget = UINT64_MAX;
  bool over_budget = false;
  // One more candidate looked at: false (and failed, over_budget) once past the budget.
  bool examine() {
    if (++examined <= budget) return true;
    failed = over_budget = true;
    return false;
  }
};

// Makes `world` answer every query from `served->graph`, the graph current when the query
// runs. Call after rasqal_world_open.
void serve_from(rasqal_world* world, Served* served);

}  // namespace skillbus::wm::sparql_detail
