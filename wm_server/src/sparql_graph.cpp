// The indexed graph and the Rasqal triples source over it (see sparql_graph.hpp).
#include "sparql_graph.hpp"

#include <cstring>
#include <memory>
#include <optional>

#include "skillbus/wm/model.hpp"

// Exported by librasqal and used by its own triples source, declared only in its internal
// header: the same conversion of a parsed term and the same RDF term equality as Rasqal's
// source, so that a query's answers do not depend on which source served it.
extern "C" {
rasqal_literal* rasqal_new_literal_from_term(rasqal_world* world, raptor_term* term);
int rasqal_literal_equals_flags(rasqal_literal* l1, rasqal_literal* l2, int flags, int* error_p);
}

namespace skillbus::wm::sparql_detail {

namespace {

// The index key of a term: IRIs and blank nodes only (RDF term equality between them is
// equality of these strings); a literal has none, a pattern bound to one is narrowed by
// its other parts and confirmed by Rasqal's comparison.
std::optional<std::string> key_of(const raptor_term* t) {
  if (t->type == RAPTOR_TERM_TYPE_URI) {
    size_t n = 0;
    const unsigned char* s = raptor_uri_as_counted_string(t->value.uri, &n);
    return "<" + std::string(reinterpret_cast<const char*>(s), n);
  }
  if (t->type == RAPTOR_TERM_TYPE_BLANK)
    return "_:" + std::string(reinterpret_cast<const char*>(t->value.blank.string), t->value.blank.string_len);
  return std::nullopt;
}

std::optional<std::string> key_of(rasqal_literal* l) {
  if (l->type == RASQAL_LITERAL_URI && l->value.uri) {
    size_t n = 0;
    const unsigned char* s = raptor_uri_as_counted_string(l->value.uri, &n);
    return "<" + std::string(reinterpret_cast<const char*>(s), n);
  }
  if (l->type == RASQAL_LITERAL_BLANK && l->string)
    return "_:" + std::string(reinterpret_cast<const char*>(l->string), l->string_len);
  return std::nullopt;
}

bool same_term(rasqal_literal* a, rasqal_literal* b) {
  int error = 0;
  return rasqal_literal_equals_flags(a, b, RASQAL_COMPARE_RDF, &error) && !error;
}

struct ParseState {
  IndexedGraph* graph;
  std::unordered_map<std::string, rasqal_literal*>* terms;
  bool failed = false;
};

// One Rasqal term per IRI or blank node (shared by reference count), a literal each time.
rasqal_literal* term(ParseState& st, raptor_term* t) {
  const auto key = key_of(t);
  if (key) {
    auto it = st.terms->find(*key);
    if (it != st.terms->end()) return rasqal_new_literal_from_literal(it->second);
  }
  rasqal_literal* l = rasqal_new_literal_from_term(st.graph->world(), t);
  if (l && key) (*st.terms)[*key] = rasqal_new_literal_from_literal(l);
  return l;
}

void on_statement(void* user, raptor_statement* statement) {
  auto& st = *static_cast<ParseState*>(user);
  rasqal_literal* s = term(st, statement->subject);
  rasqal_literal* p = term(st, statement->predicate);
  rasqal_literal* o = term(st, statement->object);
  if (!s || !p || !o) {
    for (rasqal_literal* l : {s, p, o})
      if (l) rasqal_free_literal(l);
    st.failed = true;
    return;
  }
  st.graph->add(s, p, o);
}

}  // namespace

IndexedGraph::IndexedGraph(rasqal_world* world, const std::string& turtle) : world_(world) {
  raptor_world* rw = rasqal_world_get_raptor(world);
  ParseState st{this, &terms_};
  std::unique_ptr<raptor_parser, void (*)(raptor_parser*)> parser(raptor_new_parser(rw, "turtle"),
                                                                  raptor_free_parser);
  std::unique_ptr<raptor_uri, void (*)(raptor_uri*)> base(
      raptor_new_uri(rw, reinterpret_cast<const unsigned char*>("http://skillbus.invalid/world")), raptor_free_uri);
  if (!parser || !base) throw WmError("SPARQL: cannot read the world");
  raptor_parser_set_statement_handler(parser.get(), &st, on_statement);
  int rc = raptor_parser_parse_start(parser.get(), base.get());
  if (rc == 0)
    rc = raptor_parser_parse_chunk(parser.get(), reinterpret_cast<const unsigned char*>(turtle.data()), turtle.size(),
                                   1);
  if (rc != 0 || st.failed) {
    clear();  // (the destructor does not run for a constructor that throws)
    throw WmError("SPARQL: the world's graph does not parse as Turtle (a bug of the server)");
  }
}

IndexedGraph::~IndexedGraph() { clear(); }

void IndexedGraph::clear() {
  for (rasqal_triple* t : triples_) rasqal_free_triple(t);
  triples_.clear();
  for (auto& [key, l] : terms_) rasqal_free_literal(l);
  terms_.clear();
}

void IndexedGraph::add(rasqal_literal* s, rasqal_literal* p, rasqal_literal* o) {
  const auto i = static_cast<uint32_t>(triples_.size());
  triples_.push_back(rasqal_new_triple(s, p, o));
  if (auto k = key_of(s)) by_subject_[*k].push_back(i);
  if (auto k = key_of(p)) by_predicate_[*k].push_back(i);
  if (auto k = key_of(o)) by_object_[*k].push_back(i);
}

const std::vector<uint32_t>* IndexedGraph::candidates(rasqal_literal* s, rasqal_literal* p, rasqal_literal* o,
                                                      bool& all) const {
  static const std::vector<uint32_t> none;
  const std::vector<uint32_t>* best = nullptr;
  auto narrow = [&](rasqal_literal* part, const Index& index) -> bool {
    if (!part) return true;
    const auto key = key_of(part);
    if (!key) return true;  // (a literal: confirmed later)
    auto it = index.find(*key);
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
               rasqal_triple* pattern) {
  rtm->bind_match = bind_match;
  rtm->next_match = next_match;
  rtm->is_end = is_end;
  rtm->finish = finish_match;
  auto* m = new Match;
  rtm->user_data = m;
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
  if (pattern->origin || !graph) {
    // The world is one graph without a name: a GRAPH pattern matches nothing (as it did
    // with Rasqal's own source and a background graph).
    if (pattern->origin) {
      rasqal_variable* var = rasqal_literal_as_variable(pattern->origin);
      if (var && (meta->parts & RASQAL_TRIPLE_ORIGIN)) rasqal_variable_set_value(var, nullptr);
      meta->bindings[3] = var;
    }
    m->list = &nothing;
    return 0;
  }
  m->list = graph->candidates(m->want[0], m->want[1], m->want[2], m->all);
  m->settle();
  return 0;
}

int triple_present(rasqal_triples_source*, void* user_data, rasqal_triple* t) {
  const IndexedGraph* graph = static_cast<SourceData*>(user_data)->graph;
  if (!graph || t->origin) return 0;
  Match m;
  m.graph = graph;
  m.want[0] = t->subject;  // (borrowed: not freed, m is not finished)
  m.want[1] = t->predicate;
  m.want[2] = t->object;
  m.list = graph->candidates(t->subject, t->predicate, t->object, m.all);
  m.settle();
  const bool found = m.pos < m.end();
  return found ? 1 : 0;
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
