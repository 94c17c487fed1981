// SPARQL 1.1 queries through Rasqal (the Redland query library): no hand-written query
// engine. The data is one graph (the ontology, the scene's other triples and the world's
// elements), given by the caller and taken once per version (sparql_graph.hpp); the
// query may read nothing else: FROM, FROM NAMED and SERVICE (which would make the engine
// read files or the network) are refused.
#include "skillbus/wm/sparql.hpp"

#include <rasqal.h>

#include <algorithm>
#include <cctype>
#include <cstdlib>
#include <memory>
#include <nlohmann/json.hpp>
#include <regex>
#include <set>

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

// A term of a graph result as SPARQL 1.1 JSON writes a binding's value.
nlohmann::json term_json(const raptor_term* t) {
  auto text = [](const unsigned char* s, size_t n) { return std::string(reinterpret_cast<const char*>(s), n); };
  if (t->type == RAPTOR_TERM_TYPE_URI) {
    size_t n = 0;
    const unsigned char* s = raptor_uri_as_counted_string(t->value.uri, &n);
    return {{"type", "uri"}, {"value", text(s, n)}};
  }
  if (t->type == RAPTOR_TERM_TYPE_BLANK)
    return {{"type", "bnode"}, {"value", text(t->value.blank.string, t->value.blank.string_len)}};
  nlohmann::json v = {{"type", "literal"}, {"value", text(t->value.literal.string, t->value.literal.string_len)}};
  if (t->value.literal.language)
    v["xml:lang"] = text(t->value.literal.language, t->value.literal.language_len);
  if (t->value.literal.datatype) {
    size_t n = 0;
    const unsigned char* s = raptor_uri_as_counted_string(t->value.literal.datatype, &n);
    v["datatype"] = text(s, n);
  }
  return v;
}

// A CONSTRUCT's triples, each once, as SPARQL 1.1 JSON results with the variables subject,
// predicate and object (the JSON results format has no graphs; SkiROS2's query_ontology
// gives a CONSTRUCT's triples as rows of three values, as rdflib iterates its graph).
// Stops (returns "" with `over` set) once the rows pass `max_bytes`.
std::string graph_results_json(rasqal_query_results* results, size_t max_bytes, bool& over) {
  nlohmann::json rows = nlohmann::json::array();
  std::set<std::string> seen;  // (a graph is a set: Rasqal gives a triple once per solution that makes it)
  size_t bytes = 0;
  for (const raptor_statement* t = rasqal_query_results_get_triple(results); t;
       t = rasqal_query_results_next_triple(results) ? nullptr : rasqal_query_results_get_triple(results)) {
    nlohmann::json row = {{"subject", term_json(t->subject)},
                          {"predicate", term_json(t->predicate)},
                          {"object", term_json(t->object)}};
    std::string text = row.dump();
    const size_t size = text.size();
    if (seen.insert(std::move(text)).second) {
      rows.push_back(std::move(row));
      if ((bytes += size + 1) > max_bytes) {
        over = true;
        return "";
      }
    }
  }
  nlohmann::json out = {{"head", {{"vars", {"subject", "predicate", "object"}}}},
                        {"results", {{"bindings", std::move(rows)}}}};
  return out.dump();
}

// Raptor writes the results here: kept up to `max` bytes, then counted only (a query whose
// results no reply carries must not take the server's memory first).
// Past it the triples source is told to stop, so that the rows end soon (Rasqal's writer
// goes on while rows come, whatever the stream says).
struct BoundedText {
  std::string text;
  size_t max = 0;
  size_t bytes = 0;  // written, kept or not
  sparql_detail::Served* served = nullptr;

  static int write_bytes(void* self, const void* ptr, size_t size, size_t nmemb) {
    auto* b = static_cast<BoundedText*>(self);
    const size_t n = size * nmemb;
    b->bytes += n;
    if (b->bytes <= b->max)
      b->text.append(static_cast<const char*>(ptr), n);
    else
      b->served->stop = true;
    return static_cast<int>(nmemb);
  }
  static int write_byte(void* self, const int byte) {
    const char c = static_cast<char>(byte);
    return write_bytes(self, &c, 1, 1) == 1 ? 0 : 1;
  }
  bool over() const { return bytes > max; }
};

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
  // Rasqal sorts ORDER BY and DISTINCT rows into an unbalanced binary tree (rasqal_map),
  // which rows in order or with equal keys make a list: time grows with the square of the
  // rows (20,000 rows with one key took 11 s here), and the tree is walked recursively.
  // Such a query may look at fewer triples (kMaxExaminedSorted).
  raptor_sequence* order = rasqal_query_get_order_conditions_sequence(q.get());
  const bool sorts = (order && raptor_sequence_size(order) > 0) || rasqal_query_get_distinct(q.get()) != 0;
  const uint64_t budget = sorts ? std::min(max_examined, kMaxExaminedSorted) : max_examined;
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
  impl_->served.failed = impl_->served.over_budget = impl_->served.stop = false;
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
    BoundedText out;
    out.max = max_bytes;
    out.served = &impl_->served;
    raptor_iostream_handler handler{};
    handler.version = 2;
    handler.write_byte = &BoundedText::write_byte;
    handler.write_bytes = &BoundedText::write_bytes;
    raptor_iostream* sink = raptor_new_iostream_from_handler(rw, &out, &handler);
    if (!sink) throw WmError("SPARQL: cannot write the results");
    const int w = rasqal_query_results_write(sink, results.get(), "json", nullptr, nullptr, base.get());
    raptor_free_iostream(sink);
    if (w != 0) throw WmError("SPARQL: " + (error.empty() ? std::string("cannot write the results") : error));
    too_large = out.over();
    json = std::move(out.text);
  }
  if (impl_->served.over_budget)
    throw WmError("SPARQL: the query looked at more than " + std::to_string(budget) +
                  " triples of the world and was stopped (a pattern that shares no variable with the others "
                  "multiplies the rows by the whole graph): join its patterns by variables, or narrow them" +
                  (budget < max_examined ? std::string("; with ORDER BY or DISTINCT the bound is lower: the server's "
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
