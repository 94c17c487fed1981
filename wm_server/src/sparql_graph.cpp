// The indexed graph and the Rasqal triples source over it (see sparql_graph.hpp).
#include "sparql_graph.hpp"

#include <cstdlib>
#include <cstring>
#include <memory>
#include <new>

#include "skillbus/wm/model.hpp"

// Exported by librasqal and used by its own triples source, declared only in its internal
// header: the same RDF term equality as Rasqal's source, so that a query's answers do not
// depend on which source served it (the public rasqal_literal_same_term compares by other
// rules). Were it ever gone, the build would fail to link, not answer otherwise.
extern "C" {
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

namespace {

// A copy Rasqal takes and frees (its allocator is malloc's).
unsigned char* owned_copy(const std::string& text) {
  auto* out = static_cast<unsigned char*>(std::malloc(text.size() + 1));
  if (!out) throw std::bad_alloc();
  std::memcpy(out, text.c_str(), text.size() + 1);
  return out;
}

}  // namespace

rasqal_literal* IndexedGraph::term(const Term& t) {
  raptor_world* rw = rasqal_world_get_raptor(world_);
  if (t.kind == Term::Iri) {
    rasqal_literal*& by_text = iri_texts_[t.value];  // (a text resolved once: most IRIs recur)
    if (by_text) return rasqal_new_literal_from_literal(by_text);
    // (as Raptor's Turtle parser makes every IRI it reads: against the base, which leaves
    // an absolute IRI as it is; one raptor_uri per IRI, Raptor interns them)
    raptor_uri* iri = raptor_new_uri_relative_to_base(rw, base_, reinterpret_cast<const unsigned char*>(t.value.c_str()));
    if (!iri) throw WmError("SPARQL: the world's graph has an IRI that Raptor refuses: <" + t.value + ">");
    rasqal_literal** slot = nullptr;
    try {
      slot = &iris_[iri];
    } catch (...) {
      raptor_free_uri(iri);
      throw;
    }
    rasqal_literal*& kept = *slot;
    if (kept) {
      raptor_free_uri(iri);
    } else {
      kept = rasqal_new_uri_literal(world_, iri);  // (takes the IRI)
      if (!kept) throw std::bad_alloc();
    }
    by_text = rasqal_new_literal_from_literal(kept);
    return rasqal_new_literal_from_literal(kept);
  }
  if (t.kind == Term::Blank) {
    const std::string id = "graphid0_" + t.value;
    rasqal_literal*& kept = blanks_[id];
    if (kept) return rasqal_new_literal_from_literal(kept);
    rasqal_literal* l = rasqal_new_simple_literal(world_, RASQAL_LITERAL_BLANK, owned_copy(id));
    if (!l) throw std::bad_alloc();
    kept = rasqal_new_literal_from_literal(l);
    return l;
  }
  // (the copies are made before the datatype, and all three are Rasqal's from the call on,
  // even when it fails)
  std::unique_ptr<unsigned char, void (*)(void*)> text(owned_copy(t.value), std::free);
  std::unique_ptr<unsigned char, void (*)(void*)> lang(t.lang.empty() ? nullptr : owned_copy(t.lang), std::free);
  raptor_uri* datatype = nullptr;
  if (!t.datatype.empty()) {
    datatype = raptor_new_uri_relative_to_base(rw, base_, reinterpret_cast<const unsigned char*>(t.datatype.c_str()));
    if (!datatype) throw WmError("SPARQL: the world's graph has a datatype that Raptor refuses: <" + t.datatype + ">");
  }
  rasqal_literal* l = rasqal_new_string_literal(world_, text.release(), reinterpret_cast<char*>(lang.release()),
                                                datatype, nullptr);
  if (!l) throw WmError("SPARQL: the world's graph has a literal that Rasqal refuses: \"" + t.value + "\"");
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
  rasqal_triple* t = nullptr;
  Key keys[3];
  try {
    keys[0] = key_of(s);  // (before the triple owns the terms)
    keys[1] = key_of(p);
    keys[2] = key_of(o);
    triples_.reserve(triples_.size() + 1);
  } catch (...) {
    for (rasqal_literal* l : {s, p, o}) rasqal_free_literal(l);
    throw;
  }
  t = rasqal_new_triple(s, p, o);  // (frees the three when it fails)
  if (!t) throw std::bad_alloc();
  triples_.push_back(t);  // (room reserved: does not throw)
  Index* indexes[3] = {&by_subject_, &by_predicate_, &by_object_};
  for (int k = 0; k < 3; ++k)
    if (keys[k].kind == Key::kIndexed) (*indexes[k])[keys[k].id].push_back(i);
}

IndexedGraph::IndexedGraph(rasqal_world* world, const std::vector<Triple>& triples) : world_(world) {
  raptor_world* rw = rasqal_world_get_raptor(world);
  base_ = raptor_new_uri(rw, reinterpret_cast<const unsigned char*>("http://skillbus.invalid/world"));
  if (!base_) throw WmError("SPARQL: cannot make the world's base IRI");
  try {
    // The IRI index relies on one raptor_uri per IRI (Raptor's default, URI interning):
    // were it off, equal IRIs would be told apart and matches missed; checked, not assumed.
    raptor_uri* again = raptor_new_uri(rw, reinterpret_cast<const unsigned char*>("http://skillbus.invalid/world"));
    const bool interned = again == base_;
    if (again) raptor_free_uri(again);
    if (!interned) throw WmError("SPARQL: Raptor does not intern IRIs in this world");
    triples_.reserve(triples.size());
    for (const Triple& t : triples) {
      rasqal_literal* s = term(t.s);
      rasqal_literal* p = nullptr;
      rasqal_literal* o = nullptr;
      try {
        p = term(t.p);
        o = term(t.o);
      } catch (...) {
        for (rasqal_literal* l : {s, p})
          if (l) rasqal_free_literal(l);
        throw;
      }
      add(s, p, o);  // (takes the three)
    }
  } catch (...) {
    free_terms();  // (the destructor does not run for a constructor that throws)
    throw;
  }
}

IndexedGraph::~IndexedGraph() { free_terms(); }

void IndexedGraph::free_terms() {
  if (base_) raptor_free_uri(base_);
  base_ = nullptr;
  for (rasqal_triple* t : triples_) rasqal_free_triple(t);
  triples_.clear();
  for (auto& [iri, l] : iris_)
    if (l) rasqal_free_literal(l);
  iris_.clear();
  for (auto& [text, l] : iri_texts_)
    if (l) rasqal_free_literal(l);
  iri_texts_.clear();
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
  Served* served;
};

// One triple pattern being matched: the candidates and what each part must equal.
struct Match {
  Served* served = nullptr;  // (counts the candidates looked at)
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
  void settle() {  // on to the first candidate from `pos` that matches (or the end, past the budget)
    for (; pos < end(); ++pos) {
      if (!served->examine()) {
        pos = end();
        return;
      }
      if (matches(triple())) return;
    }
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
  Served* served = static_cast<SourceData*>(user_data)->served;
  auto* m = new (std::nothrow) Match;
  rtm->user_data = m;
  if (!m) {
    served->failed = true;
    return -1;  // (Rasqal then finishes the match: finish_match takes no Match)
  }
  const IndexedGraph* graph = served->graph;
  m->served = served;
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
    served->failed = true;
    return -1;
  }
  m->settle();
  return 0;
}

int triple_present(rasqal_triples_source*, void* user_data, rasqal_triple* t) noexcept {
  Served* served = static_cast<SourceData*>(user_data)->served;
  const IndexedGraph* graph = served->graph;
  if (!graph || t->origin) return 0;
  Match m;
  m.served = served;
  m.graph = graph;
  m.want[0] = t->subject;  // (borrowed: not freed, m is not finished)
  m.want[1] = t->predicate;
  m.want[2] = t->object;
  try {
    m.list = graph->candidates(t->subject, t->predicate, t->object, m.all);
  } catch (...) {
    served->failed = true;
    return 0;
  }
  m.settle();
  return m.pos < m.end() ? 1 : 0;
}

void free_source(void*) {}  // (the graph is the engine's)

int support_feature(void*, rasqal_triples_source_feature) { return 0; }

int init_source(rasqal_query*, void* factory_user_data, void* user_data, rasqal_triples_source* rts,
                rasqal_triples_error_handler) {
  static_cast<SourceData*>(user_data)->served = static_cast<Served*>(factory_user_data);
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

void serve_from(rasqal_world* world, Served* served) {
  if (rasqal_set_triples_source_factory(world, register_factory, served) != 0)
    throw WmError("SPARQL: Rasqal refused the world's triples source");
}

}  // namespace skillbus::wm::sparql_detail
