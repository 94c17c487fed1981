// SPARQL 1.1 queries through Rasqal (the Redland query library): no hand-written query
// engine. The data is one graph (the ontology, the scene's other triples and the world's
// elements), given by the caller and taken once per version (sparql_graph.hpp); the
// query may read nothing else: FROM, FROM NAMED and SERVICE (which would make the engine
// read files or the network) are refused.
#include "skillbus/wm/sparql.hpp"

#include <rasqal.h>

#include <algorithm>
#include <cctype>
#include <memory>
#include <nlohmann/json.hpp>
#include <regex>
#include <unordered_set>
#include <vector>

#include "skillbus/wm/model.hpp"
#include "sparql_graph.hpp"
#include "sparql_text.hpp"

namespace skillbus::wm {

namespace {

// The first error Rasqal or Raptor reports for a query, into `error`.
void note_error(std::string& error, raptor_log_message* m) {
  if (m->level < RAPTOR_LOG_LEVEL_ERROR || !error.empty()) return;
  std::string where;
  if (m->locator && m->locator->line > 0) where = "line " + std::to_string(m->locator->line) + ": ";
  error = where + (m->text ? m->text : "error");
}

// The checks below read a query's code (sparql_code: its comments, strings and IRIs
// emptied), where a word is a keyword unless it is part of a name (?service, skiros:SERVICE).

// SERVICE as a keyword, followed by an IRI, a prefixed name or a variable: refused before
// the query is parsed. The parsed query's patterns are checked too (has_service_pattern);
// this check also finds a SERVICE inside FILTER EXISTS, which those patterns do not hold.
bool names_a_service(const std::string& code) {
  static const std::regex service(R"((^|[^A-Za-z0-9_:?$])SERVICE\s*(SILENT\s*)?([<?$:]|[A-Za-z_][A-Za-z0-9_.-]*:))",
                                  std::regex::icase);
  return std::regex_search(code, service);
}

// VALUES with one variable in its short form (VALUES ?x { a b }): Rasqal 0.9.33 reads only
// the first value and may bind the second to another variable, so such a query would answer
// wrongly without a word; the form with parentheses (VALUES (?x) { (a) (b) }) is read right.
bool has_short_values(const std::string& code) {
  static const std::regex values(R"((^|[^A-Za-z0-9_:?$])VALUES\s*[?$][A-Za-z0-9_]+\s*\{)", std::regex::icase);
  return std::regex_search(code, values);
}

// A property path (rdfs:subClassOf*, rdf:type/rdfs:subClassOf, ^p): Rasqal parses SPARQL
// 1.1 but has no property paths, so such a query fails with a bare syntax error.
bool has_property_path(const std::string& code) {
  static const std::regex path(R"([A-Za-z0-9_>][*+][\s.;}]|[A-Za-z0-9_>]/[A-Za-z<]|\s\^[A-Za-z<])");
  return std::regex_search(code, path);
}

// A SERVICE pattern anywhere in the parsed query's graph patterns (Rasqal would fetch it
// when the query runs).
bool has_service_pattern(rasqal_graph_pattern* gp) {
  if (gp == nullptr) return false;
  if (rasqal_graph_pattern_get_operator(gp) == RASQAL_GRAPH_PATTERN_OPERATOR_SERVICE) return true;
  for (int i = 0;; ++i) {
    rasqal_graph_pattern* sub = rasqal_graph_pattern_get_sub_graph_pattern(gp, i);
    if (sub == nullptr) return false;
    if (has_service_pattern(sub)) return true;
  }
}

// JSON text of `j`; bytes that are not UTF-8 (a value may hold any) become U+FFFD rather
// than an exception.
std::string json_text(const nlohmann::json& j) {
  return j.dump(-1, ' ', false, nlohmann::json::error_handler_t::replace);
}

std::string text_of(const unsigned char* s, size_t n) { return std::string(reinterpret_cast<const char*>(s), n); }

std::string text_of(raptor_uri* uri) {
  size_t n = 0;
  const unsigned char* s = raptor_uri_as_counted_string(uri, &n);
  return text_of(s, n);
}

// A value as SPARQL 1.1 JSON results write it: {"type": "uri"|"bnode"|"literal", "value"},
// a literal with its "xml:lang" or "datatype" when it has one.
nlohmann::json value_json(const char* type, std::string value, std::string lang = "", raptor_uri* datatype = nullptr) {
  nlohmann::json v = {{"type", type}, {"value", std::move(value)}};
  if (!lang.empty()) v["xml:lang"] = std::move(lang);
  if (datatype) v["datatype"] = text_of(datatype);
  return v;
}

// A term of a graph result (Raptor's).
nlohmann::json term_json(const raptor_term* t) {
  if (t->type == RAPTOR_TERM_TYPE_URI) return value_json("uri", text_of(t->value.uri));
  if (t->type == RAPTOR_TERM_TYPE_BLANK)
    return value_json("bnode", text_of(t->value.blank.string, t->value.blank.string_len));
  const raptor_term_literal_value& l = t->value.literal;
  return value_json("literal", text_of(l.string, l.string_len), l.language ? text_of(l.language, l.language_len) : "",
                    l.datatype);
}

// A binding's value (Rasqal's); false for one that has no such form.
bool literal_json(rasqal_literal* l, nlohmann::json& out) {
  switch (l->type) {
    case RASQAL_LITERAL_URI:
      out = value_json("uri", text_of(l->value.uri));
      return true;
    case RASQAL_LITERAL_BLANK:
      out = value_json("bnode", text_of(l->string, l->string_len));
      return true;
    case RASQAL_LITERAL_STRING:
      out = value_json("literal", text_of(l->string, l->string_len), l->language ? l->language : "", l->datatype);
      return true;
    default: {  // (a typed value: as the RDF term it stands for)
      std::unique_ptr<rasqal_literal, void (*)(rasqal_literal*)> node(rasqal_literal_as_node(l), rasqal_free_literal);
      const bool term = node && (node->type == RASQAL_LITERAL_URI || node->type == RASQAL_LITERAL_BLANK ||
                                 node->type == RASQAL_LITERAL_STRING);
      return term && literal_json(node.get(), out);
    }
  }
}

// SPARQL 1.1 JSON results written row by row, for a SELECT's rows and a CONSTRUCT's
// triples: each row's text made once and put in place, rows told apart where asked (a
// DISTINCT, a graph's set of triples), and never more than `max_bytes` held (over()).
class JsonRows {
 public:
  // `flags`: what "results" says beside its bindings ({} for nothing).
  JsonRows(const std::vector<std::string>& vars, const nlohmann::json& flags, size_t max_bytes) : max_(max_bytes) {
    text_ = "{\"head\":" + json_text(nlohmann::json{{"vars", vars}}) + ",\"results\":" + json_text(flags);
    text_.pop_back();  // (the flags' closing brace)
    text_ += flags.empty() ? "\"bindings\":[" : ",\"bindings\":[";
  }
  // Whether a row of this text came before (it is remembered; the rows remembered are held
  // too, up to `max_bytes` of them).
  bool met(const std::string& row) {
    if (seen_.count(row)) return true;
    if ((seen_bytes_ += row.size()) > max_) over_ = true;
    else seen_.insert(row);
    return false;
  }
  // Adds a row; false once the text would pass `max_bytes` (over()).
  bool add(const std::string& row) {
    if (over_ || text_.size() + 1 + row.size() + kEnd.size() > max_) return !(over_ = true);
    if (rows_++ > 0) text_ += ',';
    text_ += row;
    return true;
  }
  long rows() const { return rows_; }
  bool over() const { return over_; }
  std::string finish() {
    text_ += kEnd;
    over_ = over_ || text_.size() > max_;  // (no row: the head alone)
    return over_ ? "" : std::move(text_);
  }

 private:
  static inline const std::string kEnd = "]}}";
  size_t max_;
  std::string text_;
  std::unordered_set<std::string> seen_;
  size_t seen_bytes_ = 0;
  long rows_ = 0;
  bool over_ = false;
};

// A CONSTRUCT's triples, each once, as SPARQL 1.1 JSON results with the variables subject,
// predicate and object (the JSON results format has no graphs; SkiROS2's query_ontology
// gives a CONSTRUCT's triples as rows of three values, as rdflib iterates its graph).
// Stops (returns "" with `over` set) once the rows pass `max_bytes`.
std::string graph_results_json(rasqal_query_results* results, size_t max_bytes, bool& over) {
  JsonRows out({"subject", "predicate", "object"}, nlohmann::json::object(), max_bytes);
  for (const raptor_statement* t = rasqal_query_results_get_triple(results); t && !out.over();
       t = rasqal_query_results_next_triple(results) ? nullptr : rasqal_query_results_get_triple(results)) {
    const std::string row = json_text({{"subject", term_json(t->subject)},
                                       {"predicate", term_json(t->predicate)},
                                       {"object", term_json(t->object)}});
    // (a graph is a set: Rasqal gives a triple once per solution that makes it)
    if (!out.met(row)) out.add(row);
  }
  std::string json = out.finish();
  over = out.over();
  return json;
}

// A SELECT's DISTINCT, OFFSET and LIMIT, taken out of the query before it runs and applied
// to its rows here: Rasqal 0.9.33 leaks a DISTINCT query's rows, and tells them apart with
// an unbalanced tree (time with the square of the rows when they come in order).
struct Slice {
  int distinct = 0;  // the query's: 0 none, 1 DISTINCT, 2 REDUCED (here as DISTINCT: allowed)
  int offset = -1;   // -1: none
  int limit = -1;
};

Slice lift_slice(rasqal_query* q) {
  Slice s;
  if (rasqal_query_get_verb(q) != RASQAL_QUERY_VERB_SELECT) return s;
  s.distinct = rasqal_query_get_distinct(q);
  if (s.distinct == 0) return s;  // (Rasqal's own OFFSET and LIMIT serve)
  s.offset = rasqal_query_get_offset(q);
  s.limit = rasqal_query_get_limit(q);
  rasqal_query_set_distinct(q, 0);
  rasqal_query_set_offset(q, -1);
  rasqal_query_set_limit(q, -1);
  return s;
}

// A SELECT's rows (or an ASK's answer) as SPARQL 1.1 JSON results, written here rather than
// by Rasqal's writer: `slice` applied to the rows; an unbound value left out of its row (the
// format's rule; Rasqal wrote "type": "unbound", which SkiROS2's clients do not expect);
// the rows stop once past `max_bytes` (`over`). "" with `error` set for a value with no
// JSON form.
std::string bindings_json(rasqal_query_results* results, rasqal_query* q, const Slice& slice, size_t max_bytes,
                          bool& over, std::string& error) {
  if (rasqal_query_results_is_boolean(results))
    return nlohmann::json{{"head", nlohmann::json::object()},
                          {"boolean", rasqal_query_results_get_boolean(results) > 0}}
        .dump();  // (no text of a value)
  const int columns = rasqal_query_results_get_bindings_count(results);
  std::vector<std::string> names;
  for (int i = 0; i < columns; ++i)
    names.emplace_back(reinterpret_cast<const char*>(rasqal_query_results_get_binding_name(results, i)));
  const nlohmann::json flags = {{"ordered", rasqal_query_get_order_condition(q, 0) != nullptr},
                                {"distinct", slice.distinct != 0}};
  JsonRows out(names, flags, max_bytes);
  long skipped = 0;
  for (; !rasqal_query_results_finished(results) && !out.over(); rasqal_query_results_next(results)) {
    if (slice.limit >= 0 && out.rows() >= slice.limit) break;
    nlohmann::json row = nlohmann::json::object();
    for (int i = 0; i < columns; ++i) {
      rasqal_literal* l = rasqal_query_results_get_binding_value(results, i);
      if (!l) continue;
      nlohmann::json v;
      if (!literal_json(l, v)) {
        error = "the value of ?" + names[i] + " has no SPARQL JSON form";
        return "";
      }
      row[names[i]] = std::move(v);
    }
    const std::string text = json_text(row);
    if (slice.distinct && out.met(text)) continue;  // (the rows skipped by OFFSET are met too)
    if (slice.offset > 0 && skipped < slice.offset) {
      ++skipped;
      continue;
    }
    out.add(text);
  }
  std::string json = out.finish();
  over = out.over();
  return json;
}

}  // namespace

struct SparqlEngine::Impl {
  std::unique_ptr<rasqal_world, void (*)(rasqal_world*)> world{rasqal_new_world(), rasqal_free_world};
  std::unique_ptr<sparql_detail::IndexedGraph> graph;
  sparql_detail::Served served;  // (what the triples source serves)
  int64_t version = 0;
  int64_t reads = 0;
  std::string* error = nullptr;  // the running query's (the log handler outlives every query)
};

namespace {

// (`user`: where the running query's error goes, nullptr between queries)
void on_engine_log(void* user, raptor_log_message* m) noexcept {
  std::string* error = *static_cast<std::string**>(user);
  try {
    if (error) note_error(*error, m);
  } catch (...) {  // (nothing through Raptor's C; a message lost to a full memory)
  }
}

}  // namespace

SparqlEngine::SparqlEngine() : impl_(std::make_unique<Impl>()) {
  if (!impl_->world || rasqal_world_open(impl_->world.get())) throw WmError("SPARQL: cannot start Rasqal");
  rasqal_world_set_log_handler(impl_->world.get(), &impl_->error, on_engine_log);
  sparql_detail::serve_from(impl_->world.get(), &impl_->served);
}

SparqlEngine::~SparqlEngine() {
  impl_->served.graph = nullptr;
  impl_->graph.reset();  // (its terms belong to the world: freed before it)
}

int64_t SparqlEngine::graphs_read() const { return impl_->reads; }

std::string SparqlEngine::query_json(const std::string& query, int64_t version,
                                     const std::function<std::vector<Triple>()>& graph, const Prefixes& prefixes,
                                     size_t max_bytes, uint64_t max_examined) {
  const std::string code = sparql_detail::sparql_code(query);
  if (names_a_service(code)) throw WmError("SPARQL: SERVICE is not allowed: a query reads the world model only");
  if (has_short_values(code))
    throw WmError("SPARQL: write VALUES with parentheses, VALUES (?x) { (a) (b) }: the server's SPARQL engine, "
                  "Rasqal, reads VALUES ?x { a b } wrongly (only its first value)");
  std::string error;
  impl_->error = &error;
  struct Forget {
    Impl& impl;
    ~Forget() { impl.error = nullptr; }
  } forget{*impl_};
  rasqal_world* world = impl_->world.get();
  raptor_world* rw = rasqal_world_get_raptor(world);
  // The prefixes the world model knows are declared for the query, as SkiROS2's ontology
  // server does (a query may say skiros:Product without a PREFIX line).
  std::string text;
  for (const auto& [p, ns] : prefixes.all()) text += "PREFIX " + p + ": <" + ns + ">\n";
  text += query;
  text += '\n';  // (Rasqal's lexer takes a comment only up to a line break: one on the last line was a syntax error)
  std::unique_ptr<rasqal_query, void (*)(rasqal_query*)> q(rasqal_new_query(world, "sparql", nullptr),
                                                          rasqal_free_query);
  std::unique_ptr<raptor_uri, void (*)(raptor_uri*)> base(
      raptor_new_uri(rw, reinterpret_cast<const unsigned char*>("http://skillbus.invalid/world")), raptor_free_uri);
  if (!q || !base) throw WmError("SPARQL: cannot make a query");
  if (rasqal_query_prepare(q.get(), reinterpret_cast<const unsigned char*>(text.c_str()), base.get()) != 0)
    throw WmError("SPARQL: " + (error.empty() ? std::string("the query does not parse") : error) +
                  (has_property_path(code)
                       ? " (the server's SPARQL engine, Rasqal, has no property paths such as rdfs:subClassOf* or "
                         "rdf:type/rdfs:subClassOf: the client's get_sub_classes, get_individuals and "
                         "get_sub_properties answer those questions)"
                       : ""));
  if (has_service_pattern(rasqal_query_get_query_graph_pattern(q.get())))
    throw WmError("SPARQL: SERVICE is not allowed: a query reads the world model only");
  if (rasqal_query_get_verb(q.get()) == RASQAL_QUERY_VERB_DESCRIBE)
    throw WmError("SPARQL: DESCRIBE is not answered (the server's SPARQL engine, Rasqal, does not implement it): "
                  "ask SELECT ?p ?o WHERE { <the element> ?p ?o }");
  raptor_sequence* graphs = rasqal_query_get_data_graph_sequence(q.get());
  if (graphs && raptor_sequence_size(graphs) > 0)
    throw WmError("SPARQL: FROM and FROM NAMED are not allowed: a query reads the world model only");
  // Rasqal sorts ORDER BY's rows into an unbalanced binary tree (rasqal_map), which rows in
  // order or with equal keys make a list: time grows with the square of the rows (20,000
  // rows with one key took 11 s here), and the tree is walked recursively. Such a query may
  // look at fewer triples (kMaxExaminedSorted). (A DISTINCT is done here: lift_slice.)
  raptor_sequence* order = rasqal_query_get_order_conditions_sequence(q.get());
  const bool sorts = order && raptor_sequence_size(order) > 0;
  const uint64_t budget = sorts ? std::min(max_examined, kMaxExaminedSorted) : max_examined;
  const Slice slice = lift_slice(q.get());
  error.clear();  // (the query is prepared: what is logged from here on is the graph's or the run's)
  if (!impl_->graph || impl_->version != version) {  // (a query that does not parse reads no graph)
    impl_->served.graph = nullptr;
    impl_->graph.reset();
    impl_->graph = std::make_unique<sparql_detail::IndexedGraph>(world, graph());  // (throws naming what it could not make)
    if (!error.empty()) {  // (a term Rasqal logged as bad while it was made)
      impl_->graph.reset();
      throw WmError("SPARQL: the world's graph cannot be made: " + error);
    }
    impl_->version = version;
    ++impl_->reads;
  }
  impl_->served.graph = impl_->graph.get();
  impl_->served.failed = impl_->served.over_budget = false;
  impl_->served.examined = 0;
  impl_->served.budget = budget;
  std::unique_ptr<rasqal_query_results, void (*)(rasqal_query_results*)> results(rasqal_query_execute(q.get()),
                                                                                rasqal_free_query_results);
  if (!results) throw WmError("SPARQL: " + (error.empty() ? std::string("the query failed") : error));
  std::string json;
  bool too_large = false;
  if (rasqal_query_results_is_graph(results.get())) {
    json = graph_results_json(results.get(), max_bytes, too_large);
  } else {
    std::string unwritable;
    json = bindings_json(results.get(), q.get(), slice, max_bytes, too_large, unwritable);
    if (!unwritable.empty()) throw WmError("SPARQL: cannot write the results: " + unwritable);
  }
  if (impl_->served.over_budget)
    throw WmError("SPARQL: the query looked at more than " + std::to_string(budget) +
                  " triples of the world and was stopped (a pattern that shares no variable with the others "
                  "multiplies the rows by the whole graph): join its patterns by variables, or narrow them" +
                  (budget < max_examined ? std::string("; with ORDER BY the bound is lower: the server's "
                                                       "SPARQL engine, Rasqal, sorts in time that grows with the "
                                                       "square of the rows (sort on the client instead)")
                                         : std::string()));
  if (too_large)
    throw WmError("SPARQL: the results are over " + std::to_string(max_bytes) +
                  " bytes, more than a reply carries: add LIMIT and OFFSET to the query");
  // (a pattern that could not be matched, or an error Rasqal logged while the rows came,
  // ends the rows early without failing the writer: partial results are no answer)
  if (impl_->served.failed || !error.empty())
    throw WmError("SPARQL: the query failed while it ran" + (error.empty() ? std::string() : ": " + error));
  return json;
}

}  // namespace skillbus::wm
