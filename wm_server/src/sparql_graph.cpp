// The indexed graph and the Rasqal triples source over it (see sparql_graph.hpp).
#include "sparql_graph.hpp"

#include <cstdlib>
#include <cstring>
#include <new>
#include <tuple>
#include <memory>
#include <optional>

#include "skillbus/wm/model.hpp"

// Exported by librasqal and used by its own triples source, declared only in its internal
// header: the same conversion of a parsed term and the same RDF term equality as Rasqal's
// source, so that a query's answers do not depend on which source served it (the public
// rasqal_literal_same_term compares by other rules). Were they ever gone, the build would
// fail to link, not answer otherwise.
extern "C" {
rasqal_literal* rasqal_new_literal_from_term(rasqal_world* world, raptor_term* term);
int rasqal_literal_equals_flags(rasqal_literal* l1, rasqal_literal* l2, int flags, int* error_p);
}

namespace skillbus::wm::sparql_detail {

namespace {

std::string blank_label(const rasqal_literal* l) {
  return std::string(reinterpret_cast<const char*>(l->string), l->string_len);
}

bool same_term(rasqal_literal* a, rasqal_literal* b) {
  int error = 0;
  return rasqal_literal_equals_flags(a, b, RASQAL_COMPARE_RDF, &error) && !error;
}

}  // namespace

// Raptor's callbacks are C: nothing may throw through them (a failure is noted and the
// constructor throws after the parse).
struct IndexedGraph::Parsing {
  static void on_statement(void* user, raptor_statement* statement) noexcept {
    auto& g = *static_cast<IndexedGraph*>(user);
    rasqal_literal* parts[3] = {nullptr, nullptr, nullptr};
    try {
      parts[0] = g.term(statement->subject);
      parts[1] = g.term(statement->predicate);
      parts[2] = g.term(statement->object);
      if (parts[0] && parts[1] && parts[2]) {
        g.add(parts[0], parts[1], parts[2]);  // (takes them, even when it fails)
        return;
      }
    } catch (...) {
    }
    for (rasqal_literal* l : parts)
      if (l) rasqal_free_literal(l);
    g.failed_ = true;
  }

  // The data's blank nodes named apart from those Rasqal makes for a query (BNODE(), a
  // CONSTRUCT's template), as Rasqal's own source names them: a labelled one
  // "graphid0_<label>", an anonymous one "graphid0-<n>" (numbered per graph, so the same
  // graph gives the same names).
  static unsigned char* blank_id(void* user, unsigned char* label) noexcept {
    auto& g = *static_cast<IndexedGraph*>(user);
    std::string id;
    try {
      id = label ? "graphid0_" + std::string(reinterpret_cast<const char*>(label))
                 : "graphid0-" + std::to_string(++g.anonymous_);
    } catch (...) {
      g.failed_ = true;
    }
    if (label) raptor_free_memory(label);
    auto* out = static_cast<unsigned char*>(std::malloc(id.size() + 1));  // (Raptor frees it)
    if (!out) {
      g.failed_ = true;
      return nullptr;
    }
    std::memcpy(out, id.c_str(), id.size() + 1);
    return out;
  }
};

rasqal_literal* IndexedGraph::term(raptor_term* t) {
  // One Rasqal term per IRI (Raptor interns IRIs: one raptor_uri per IRI in a world) and
  // per blank node, shared by reference count; a literal each time.
  rasqal_literal** kept = nullptr;
  if (t->type == RAPTOR_TERM_TYPE_URI)
    kept = &iris_[t->value.uri];
  else if (t->type == RAPTOR_TERM_TYPE_BLANK)
    kept = &blanks_[std::string(reinterpret_cast<const char*>(t->value.blank.string), t->value.blank.string_len)];
  if (kept && *kept) return rasqal_new_literal_from_literal(*kept);
  rasqal_literal* l = rasqal_new_literal_from_term(world_, t);
  if (l && kept) *kept = rasqal_new_literal_from_literal(l);  // (one reference kept here)
  return l;
}

IndexedGraph::Key IndexedGraph::key_of(const rasqal_literal* l) const {
  if (l->type == RASQAL_LITERAL_URI && l->value.uri) return {Key::kIndexed, l->value.uri};
  if (l->type == RASQAL_LITERAL_BLANK && l->string) {
    auto it = blanks_.find(blank_label(l));
    return it == blanks_.end() || !it->second ? Key{Key::kAbsent, nullptr} : Key{Key::kIndexed, it->second};
  }
  return {Key::kLiteral, nullptr};
}

void IndexedGraph::add(rasqal_literal* s, rasqal_literal* p, rasqal_literal* o) {
  const auto i = static_cast<uint32_t>(triples_.size());
  const Key keys[3] = {key_of(s), key_of(p), key_of(o)};  // (before the triple owns the terms)
  rasqal_triple* t = rasqal_new_triple(s, p, o);         // (frees the three when it fails)
  if (!t) {
    failed_ = true;
    return;
  }
  triples_.push_back(t);
  Index* indexes[3] = {&by_subject_, &by_predicate_, &by_object_};
  for (int k = 0; k < 3; ++k)
    if (keys[k].kind == Key::kIndexed) (*indexes[k])[keys[k].id].push_back(i);
}

IndexedGraph::IndexedGraph(rasqal_world* world, const std::string& turtle) : world_(world) {
  raptor_world* rw = rasqal_world_get_raptor(world);
  std::unique_ptr<raptor_parser, void (*)(raptor_parser*)> parser(raptor_new_parser(rw, "turtle"),
                                                                  raptor_free_parser);
  std::unique_ptr<raptor_uri, void (*)(raptor_uri*)> base(
      raptor_new_uri(rw, reinterpret_cast<const unsigned char*>("http://skillbus.invalid/world")), raptor_free_uri);
  if (!parser || !base) throw WmError("SPARQL: cannot read the world");
  // The IRI index relies on one raptor_uri per IRI (Raptor's default, URI interning): were
  // it off, equal IRIs would be told apart and matches missed, so it is checked, not assumed.
  std::unique_ptr<raptor_uri, void (*)(raptor_uri*)> again(
      raptor_new_uri(rw, reinterpret_cast<const unsigned char*>("http://skillbus.invalid/world")), raptor_free_uri);
  if (again.get() != base.get()) throw WmError("SPARQL: Raptor does not intern IRIs in this world");
  raptor_parser_set_statement_handler(parser.get(), this, Parsing::on_statement);
  raptor_world_set_generate_bnodeid_handler(rw, this, Parsing::blank_id);
  int rc = raptor_parser_parse_start(parser.get(), base.get());
  if (rc == 0)
    rc = raptor_parser_parse_chunk(parser.get(), reinterpret_cast<const unsigned char*>(turtle.data()), turtle.size(),
                                   1);
  raptor_world_set_generate_bnodeid_handler(rw, nullptr, nullptr);  // (Raptor's own again, for queries)
  if (rc != 0 || failed_) {
    free_terms();  // (the destructor does not run for a constructor that throws)
    throw WmError("SPARQL: the world's graph does not parse as Turtle");
  }
}

IndexedGraph::~IndexedGraph() { free_terms(); }

void IndexedGraph::free_terms() {
  for (rasqal_triple* t : triples_) rasqal_free_triple(t);
  triples_.clear();
  for (auto& [iri, l] : iris_)
    if (l) rasqal_free_literal(l);
  iris_.clear();
  for (auto& [label, l] : blanks_)
    if (l) rasqal_free_literal(l);
  blanks_.clear();
}

const std::vector<uint32_t>* IndexedGraph::candidates(rasqal_literal* s, rasqal_literal* p, rasqal_literal* o,
                                                      bool& all) const {
  static const std::vector<uint32_t> none;
  const std::vector<uint32_t>* best = nullptr;
  auto narrow = [&](rasqal_literal* part, const Index& index) -> bool {
    if (!part) return true;
    const Key key = key_of(part);
    if (key.kind == Key::kLiteral) return true;  // (confirmed later)
    if (key.kind == Key::kAbsent) return false;  // a blank node the graph does not have
    auto it = index.find(key.id);
    if (it == index.end()) return false;  // no triple has it there
    if (!best || it->second.size() < best->size()) best = &it->second;
    return true;
  };
  all = false;
  if (!narrow(s, by_subject_) || !narrow(o, by_object_) || !narrow(p, by_predicate_)) return &none;
  if (!best) all = true;
  return best;
}

namespace {

// -- Rasqal's triples source API (rasqal.h: rasqal_triples_source, rasqal_triples_match) --

struct SourceData {
  const IndexedGraph* graph;
};

// One triple pattern being matched: the candidates and what each part must equal.
struct Match {
  const IndexedGraph* graph = nullptr;
  const std::vector<uint32_t>* list = nullptr;  // (with `all`: every triple)
  bool all = false;
  size_t pos = 0;
  rasqal_literal* want[3] = {nullptr, nullptr, nullptr};  // references held; nullptr: any

  size_t end() const { return all ? graph->size() : list->size(); }
  const rasqal_triple* triple() const { return graph->at(all ? static_cast<uint32_t>(pos) : (*list)[pos]); }
  bool matches(const rasqal_triple* t) const {
    rasqal_literal* parts[3] = {t->subject, t->predicate, t->object};
    for (int i = 0; i < 3; ++i)
      if (want[i] && !same_term(parts[i], want[i])) return false;
    return true;
  }
  void settle() {  // on to the first candidate from `pos` that matches
    while (pos < end() && !matches(triple())) ++pos;
  }
};

rasqal_triple_parts bind_match(rasqal_triples_match* rtm, void*, rasqal_variable* bindings[4],
                               rasqal_triple_parts parts) {
  auto* m = static_cast<Match*>(rtm->user_data);
  const rasqal_triple* t = m->triple();
  rasqal_literal* values[3] = {t->subject, t->predicate, t->object};
  const rasqal_triple_parts bits[3] = {RASQAL_TRIPLE_SUBJECT, RASQAL_TRIPLE_PREDICATE, RASQAL_TRIPLE_OBJECT};
  int bound = 0;
  for (int i = 0; i < 3; ++i) {
    if (!bindings[i] || !(parts & bits[i])) continue;
    // A variable met twice in the pattern (?x ?p ?x) binds once, where both parts agree.
    int first = -1;
    for (int j = 0; j < i && first < 0; ++j)
      if (bindings[j] == bindings[i]) first = j;
    if (first >= 0) {
      if (!same_term(values[first], values[i])) return static_cast<rasqal_triple_parts>(0);
      continue;
    }
    rasqal_variable_set_value(bindings[i], rasqal_new_literal_from_literal(values[i]));
    bound |= bits[i];
  }
  return static_cast<rasqal_triple_parts>(bound);
}

void next_match(rasqal_triples_match* rtm, void*) {
  auto* m = static_cast<Match*>(rtm->user_data);
  ++m->pos;
  m->settle();
}

int is_end(rasqal_triples_match* rtm, void*) {
  auto* m = static_cast<Match*>(rtm->user_data);
  return !m || m->pos >= m->end();
}

void finish_match(rasqal_triples_match* rtm, void*) {
  auto* m = static_cast<Match*>(rtm->user_data);
  if (!m) return;
  for (rasqal_literal* l : m->want)
    if (l) rasqal_free_literal(l);
  delete m;
  rtm->user_data = nullptr;
}

int init_match(rasqal_triples_match* rtm, rasqal_triples_source*, void* user_data, rasqal_triple_meta* meta,
               rasqal_triple* pattern) noexcept {
  rtm->bind_match = bind_match;
  rtm->next_match = next_match;
  rtm->is_end = is_end;
  rtm->finish = finish_match;
  auto* m = new (std::nothrow) Match;
  rtm->user_data = m;
  if (!m) return -1;  // (Rasqal then finishes the match: finish_match takes no Match)
  const IndexedGraph* graph = static_cast<SourceData*>(user_data)->graph;
  m->graph = graph;
  rasqal_literal* parts[3] = {pattern->subject, pattern->predicate, pattern->object};
  const rasqal_triple_parts bits[3] = {RASQAL_TRIPLE_SUBJECT, RASQAL_TRIPLE_PREDICATE, RASQAL_TRIPLE_OBJECT};
  for (int i = 0; i < 3; ++i) {
    rasqal_variable* var = rasqal_literal_as_variable(parts[i]);
    if (var) {
      if (meta->parts & bits[i])
        rasqal_variable_set_value(var, nullptr);  // (this pattern binds it)
      else if (var->value)
        m->want[i] = rasqal_new_literal_from_literal(var->value);  // (bound by an earlier pattern)
    } else {
      m->want[i] = rasqal_new_literal_from_literal(parts[i]);
    }
    meta->bindings[i] = var;
  }
  static const std::vector<uint32_t> nothing;
  // (No pattern comes with an origin: Rasqal's GRAPH reads the query's named graphs, and
  // FROM NAMED is refused. One would match nothing: the world is one graph without a name.)
  if (pattern->origin || !graph) {
    m->list = &nothing;
    return 0;
  }
  try {
    m->list = graph->candidates(m->want[0], m->want[1], m->want[2], m->all);
  } catch (...) {  // (no exception through Rasqal's C)
    return -1;
  }
  m->settle();
  return 0;
}

int triple_present(rasqal_triples_source*, void* user_data, rasqal_triple* t) noexcept {
  const IndexedGraph* graph = static_cast<SourceData*>(user_data)->graph;
  if (!graph || t->origin) return 0;
  Match m;
  m.graph = graph;
  m.want[0] = t->subject;  // (borrowed: not freed, m is not finished)
  m.want[1] = t->predicate;
  m.want[2] = t->object;
  try {
    m.list = graph->candidates(t->subject, t->predicate, t->object, m.all);
  } catch (...) {
    return 0;
  }
  m.settle();
  return m.pos < m.end() ? 1 : 0;
}

void free_source(void*) {}  // (the graph is the engine's)

int support_feature(void*, rasqal_triples_source_feature) { return 0; }

int init_source(rasqal_query*, void* factory_user_data, void* user_data, rasqal_triples_source* rts,
                rasqal_triples_error_handler) {
  static_cast<SourceData*>(user_data)->graph = *static_cast<const IndexedGraph* const*>(factory_user_data);
  rts->version = 2;
  rts->init_triples_match = init_match;
  rts->triple_present = triple_present;
  rts->free_triples_source = free_source;
  rts->support_feature = support_feature;
  return 0;
}

int register_factory(rasqal_triples_source_factory* factory) {
  factory->version = 2;
  factory->user_data_size = sizeof(SourceData);
  factory->init_triples_source = init_source;
  return 0;
}

}  // namespace

void serve_from(rasqal_world* world, const IndexedGraph* const* graph) {
  if (rasqal_set_triples_source_factory(world, register_factory, const_cast<IndexedGraph**>(graph)) != 0)
    throw WmError("SPARQL: Rasqal refused the world's triples source");
}

}  // namespace skillbus::wm::sparql_detail
