// SPARQL 1.1 queries through Rasqal (the Redland query library): no hand-written query
// engine. The data is one graph in Turtle (the ontology, the scene's other triples and the
// world's elements), given by the caller; the query may read nothing else: FROM, FROM NAMED
// and SERVICE (which would make the engine read files or the network) are refused.
#include "skillbus/wm/sparql.hpp"

#include <rasqal.h>

#include <cctype>
#include <cstdlib>
#include <memory>
#include <regex>

#include "skillbus/wm/model.hpp"

namespace skillbus::wm {

namespace {

struct QueryState {
  std::string error;
};

void on_log(void* user, raptor_log_message* m) {
  auto* st = static_cast<QueryState*>(user);
  if (m->level < RAPTOR_LOG_LEVEL_ERROR || !st->error.empty()) return;
  std::string where;
  if (m->locator && m->locator->line > 0) where = "line " + std::to_string(m->locator->line) + ": ";
  st->error = where + (m->text ? m->text : "error");
}

// SERVICE as a keyword (outside IRIs and strings it is the only use of the word); a false
// alarm on a literal "service" only refuses a harmless query.
bool names_a_service(const std::string& query) {
  static const std::regex service(R"((^|[^A-Za-z0-9_:<"'#])SERVICE\s*(SILENT\s*)?[<?$])", std::regex::icase);
  return std::regex_search(query, service);
}

// A property path (rdfs:subClassOf*, rdf:type/rdfs:subClassOf, ^p): Rasqal parses SPARQL
// 1.1 but has no property paths, so such a query fails with a bare syntax error.
bool has_property_path(const std::string& query) {
  static const std::regex path(R"([A-Za-z0-9_>][*+][\s.;}]|[A-Za-z0-9_>]/[A-Za-z<]|\s\^[A-Za-z<])");
  return std::regex_search(query, path);
}

}  // namespace

std::string sparql_json(const std::string& query, const std::string& data_turtle, const Prefixes& prefixes,
                        size_t max_bytes) {
  if (names_a_service(query)) throw WmError("SPARQL: SERVICE is not allowed: a query reads the world model only");
  QueryState st;
  std::unique_ptr<rasqal_world, void (*)(rasqal_world*)> world(rasqal_new_world(), rasqal_free_world);
  if (!world || rasqal_world_open(world.get())) throw WmError("SPARQL: cannot start Rasqal");
  rasqal_world_set_log_handler(world.get(), &st, on_log);
  raptor_world* rw = rasqal_world_get_raptor(world.get());
  // The prefixes the world model knows are declared for the query, as SkiROS2's ontology
  // server does (a query may say skiros:Product without a PREFIX line).
  std::string text;
  for (const auto& [p, ns] : prefixes.all()) text += "PREFIX " + p + ": <" + ns + ">\n";
  text += query;
  // (the data graph borrows the stream: it must outlive the query, so it is declared first)
  std::unique_ptr<raptor_iostream, void (*)(raptor_iostream*)> in(
      raptor_new_iostream_from_string(rw, const_cast<char*>(data_turtle.data()), data_turtle.size()),
      raptor_free_iostream);
  if (!in) throw WmError("SPARQL: cannot read the world");
  std::unique_ptr<rasqal_query, void (*)(rasqal_query*)> q(rasqal_new_query(world.get(), "sparql", nullptr),
                                                          rasqal_free_query);
  std::unique_ptr<raptor_uri, void (*)(raptor_uri*)> base(
      raptor_new_uri(rw, reinterpret_cast<const unsigned char*>("http://skillbus.invalid/world")), raptor_free_uri);
  if (!q || !base) throw WmError("SPARQL: cannot make a query");
  if (rasqal_query_prepare(q.get(), reinterpret_cast<const unsigned char*>(text.c_str()), base.get()) != 0)
    throw WmError("SPARQL: " + (st.error.empty() ? std::string("the query does not parse") : st.error) +
                  (has_property_path(query)
                       ? " (the server's SPARQL engine, Rasqal, has no property paths such as rdfs:subClassOf* or "
                         "rdf:type/rdfs:subClassOf: the client's get_sub_classes, get_individuals and "
                         "get_sub_properties answer those questions)"
                       : ""));
  raptor_sequence* graphs = rasqal_query_get_data_graph_sequence(q.get());
  if (graphs && raptor_sequence_size(graphs) > 0)
    throw WmError("SPARQL: FROM and FROM NAMED are not allowed: a query reads the world model only");
  rasqal_data_graph* dg = rasqal_new_data_graph_from_iostream(world.get(), in.get(), base.get(), nullptr,
                                                              RASQAL_DATA_GRAPH_BACKGROUND, nullptr, "turtle", nullptr);
  if (!dg) throw WmError("SPARQL: cannot load the world");
  const int added = rasqal_query_add_data_graph(q.get(), dg);  // (the query owns it now)
  if (added != 0) throw WmError("SPARQL: cannot load the world");
  std::unique_ptr<rasqal_query_results, void (*)(rasqal_query_results*)> results(rasqal_query_execute(q.get()),
                                                                                rasqal_free_query_results);
  if (!results) throw WmError("SPARQL: " + (st.error.empty() ? std::string("the query failed") : st.error));
  void* out = nullptr;
  size_t out_len = 0;
  raptor_iostream* sink = raptor_new_iostream_to_string(rw, &out, &out_len, malloc);
  if (!sink) throw WmError("SPARQL: cannot write the results");
  const int w = rasqal_query_results_write(sink, results.get(), "json", nullptr, nullptr, base.get());
  raptor_free_iostream(sink);  // (finishes the string)
  std::string json(static_cast<const char*>(out ? out : ""), out_len);
  std::free(out);
  if (w != 0) throw WmError("SPARQL: " + (st.error.empty() ? std::string("cannot write the results") : st.error));
  if (json.size() > max_bytes)
    throw WmError("SPARQL: the results are " + std::to_string(json.size()) + " bytes, more than a reply carries (" +
                  std::to_string(max_bytes) + "): add LIMIT and OFFSET to the query");
  return json;
}

}  // namespace skillbus::wm
