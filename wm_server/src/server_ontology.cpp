// The world model server's ontology RPCs: what it judges by (ontology), SPARQL over it and
// the world (sparql), adding class axioms while it runs (add_axioms, SkiROS2's
// add_class), and SkiROS2's advisory lock (lock).
#include <algorithm>
#include <set>

#include <nlohmann/json.hpp>

#include "skillbus/wm/scene.hpp"
#include "skillbus/wm/server.hpp"
#include "skillbus/wm/sparql.hpp"

namespace skillbus::wm {

using namespace skillbus_msgs;

namespace {

const char* kLog = "wm_server";

// What add_axioms takes: statements about classes and relation types, never about the
// world's elements (those are written by commit, journalled and announced as changes).
void check_axiom(const Triple& t, const WorldStore& store, const Prefixes& px) {
  if (t.s.kind == Term::Blank || t.o.kind == Term::Blank)
    throw WmError("add_axioms: a blank node (e.g. an owl:Restriction) cannot be added while the server runs (its "
                  "name could clash with the loaded ones): put it in an ontology file or a scene");
  for (const Term* term : {&t.s, &t.o})
    if (term->kind == Term::Iri && store.get(px.compact(term->value)))
      throw WmError("add_axioms: " + px.compact(term->value) +
                    " is an element of the world: change elements with a transaction (commit), not as axioms");
  if (t.p.value == kRdfType && t.o.value == "http://www.w3.org/2002/07/owl#NamedIndividual")
    throw WmError("add_axioms: " + px.compact(t.s.value) +
                  " would be an owl:NamedIndividual, which a scene reads as an element: add elements with add_element");
}

// The ontology's individuals (SkiROS2's templates: owl:NamedIndividual in an ontology file
// or among a scene's axioms) with their statements: {iri: [[predicate, object, datatype
// or "" for an IRI, language], ...]}, IRIs compacted.
nlohmann::json individuals(const std::vector<Triple>& axioms, const Prefixes& px) {
  std::set<std::string> named;
  for (const auto& t : axioms)
    if (t.s.kind == Term::Iri && t.p.value == kRdfType && t.o.value == kOwlNamedIndividual) named.insert(t.s.value);
  nlohmann::json out = nlohmann::json::object();
  for (const auto& i : named) out[px.compact(i)] = nlohmann::json::array();
  for (const auto& t : axioms) {
    if (t.s.kind != Term::Iri || !named.count(t.s.value) || t.o.kind == Term::Blank) continue;
    const bool literal = t.o.kind == Term::Literal;
    out[px.compact(t.s.value)].push_back(
        {px.compact(t.p.value), literal ? t.o.value : px.compact(t.o.value),
         literal ? (t.o.datatype.empty() ? std::string("xsd:string") : px.compact(t.o.datatype)) : std::string(),
         t.o.lang});
  }
  return out;
}

bool same(const Term& a, const Term& b) {
  return a.kind == b.kind && a.value == b.value && a.datatype == b.datatype && a.lang == b.lang;
}

bool same(const Triple& a, const Triple& b) { return same(a.s, b.s) && same(a.p, b.p) && same(a.o, b.o); }

}  // namespace

std::vector<Triple> WorldModelServer::all_axioms() const {
  std::vector<Triple> all = ontology_triples_;
  append_apart(all, scene_imports_);  // (three sources, each with blank nodes of its own: one document)
  append_apart(all, scene_extra_);
  return all;
}

void WorldModelServer::add_ontology_methods() {
  // The ontology the server judges by, as Turtle (its files, what the scene imported, the
  // scene's axioms): the skill manager and the Python clients take it from here, so every
  // process of the system has one ontology.
  rpc_.add_method<wm_scene_t, wm_scene_t>("ontology", [this](const wm_scene_t&) {
    wm_scene_t out{};
    out.turtle = write_turtle(all_axioms(), prefixes_);
    out.version = store_.version();
    return out;
  });
  // SPARQL (SkiROS2's query_ontology) over the ontology, the scene's other triples and the
  // world's elements: wm_scene_t{turtle: the query} -> wm_scene_t{turtle: SPARQL 1.1 JSON
  // results, report: the prefixes as JSON, for clients that print compact names}.
  rpc_.add_method<wm_scene_t, wm_scene_t>("sparql", [this](const wm_scene_t& req) {
    wm_scene_t out{};
    try {
      // (a large result comes in chunks, docs/rpc.md; the server's reply memory bounds it)
      out.turtle = sparql_.query_json(req.turtle, store_.version(), [this] { return sparql_graph(); }, prefixes_,
                                      opt_.rpc_memory_bytes / 2, opt_.sparql_max_examined);
    } catch (const WmError& e) {
      throw RpcBadRequest(e.what());
    }
    std::string px = "{";
    for (const auto& [p, ns] : prefixes_.all()) px += (px.size() > 1 ? ",\"" : "\"") + p + "\":\"" + ns + "\"";
    out.report = px + "}";
    out.version = store_.version();
    return out;
  });
  // The class and relation-type hierarchy as the server judges by it, for clients that ask
  // about superclasses and subclasses (SkiROS2's get_super_class, get_sub_classes, ...):
  // wm_scene_t{} -> wm_scene_t{turtle: {"classes": {class: [direct superclasses]},
  // "relations": {relation: [direct superproperties]}, "individuals": the ontology's
  // individuals (templates) with their statements (see individuals()} as JSON}.
  rpc_.add_method<wm_scene_t, wm_scene_t>("hierarchy", [this](const wm_scene_t&) {
    nlohmann::json j = {{"classes", ontology_.class_parents()},
                        {"relations", ontology_.relation_parents()},
                        {"individuals", individuals(all_axioms(), prefixes_)}};
    wm_scene_t out{};
    out.turtle = j.dump();
    out.version = store_.version();
    return out;
  });
  rpc_.add_method<wm_scene_t, wm_scene_t>("add_axioms", [this](const wm_scene_t& r) { return on_add_axioms(r); });
  rpc_.add_method<wm_lock_t, wm_lock_t>("lock", [this](const wm_lock_t& r) { return on_lock(r); });
}

// Turtle statements added to the scene's axioms (so a save carries them and a restart
// keeps them); the ontology learns their classes, subclasses and relation types. Every
// replica reads the world again, the skill manager with the new ontology.
wm_scene_t WorldModelServer::on_add_axioms(const wm_scene_t& req) {
  Prefixes px = prefixes_;
  std::string text;  // the server's prefixes are declared, as for a SPARQL query (on one line: serd's
  for (const auto& [p, ns] : prefixes_.all()) text += "@prefix " + p + ": <" + ns + "> . ";  // line numbers +1)
  text += "\n";
  const std::vector<Triple> triples = parse_turtle(text + req.turtle, px, "add_axioms");
  if (triples.empty()) throw WmError("add_axioms: no statement in the request");
  for (const auto& t : triples) check_axiom(t, store_, px);
  std::vector<Triple> extra = scene_extra_;
  size_t added = 0;
  for (const auto& t : triples)
    if (std::none_of(extra.begin(), extra.end(), [&](const Triple& e) { return same(e, t); })) {
      extra.push_back(t);
      ++added;
    }
  wm_scene_t out{};
  out.report = std::to_string(added) + " new statement(s)";
  if (added > 0) {
    Ontology onto = ontology_;
    onto.add_triples(triples, px);
    OntologyLoad imported = library_.resolve(onto, px);  // (an owl:imports among them)
    std::vector<Triple> imports = scene_imports_;
    if (!imported.triples.empty()) {
      onto.add_triples(extra, px);
      append_apart(imports, imported.triples);
      for (const auto& f : imported.files) out.report += "; imported the ontology " + f;
    }
    SceneChange change;
    change.what = "the scene's axioms";
    change.ontology = std::move(onto);
    change.prefixes = std::move(px);
    change.imports = std::move(imports);
    change.extra = std::move(extra);
    change_scene(std::move(change));  // durable before the reply
    announce_reset();
  }
  out.version = store_.version();
  return out;
}

void WorldModelServer::announce_reset() {
  wm_change_t change{};
  change.version = store_.version();
  change.reset = true;
  if (opt_.wall_clock) {
    publish_change_now(change);
  } else {
    pending_changes_.push_back(change);
  }
}

wm_lock_t WorldModelServer::on_lock(const wm_lock_t& req) {
  wm_lock_t out = req;
  if (req.lock) {
    if (req.holder.empty()) throw WmError("lock: name the holder");
    out.ok = lock_holder_.empty() || lock_holder_ == req.holder;
    if (out.ok && lock_holder_.empty()) SB_INFO(kLog, "locked by " << req.holder);
    if (out.ok) lock_holder_ = req.holder;
  } else {
    out.ok = !lock_holder_.empty();
    if (out.ok) SB_INFO(kLog, "unlocked by " << req.holder << " (held by " << lock_holder_ << ")");
    lock_holder_.clear();
  }
  out.holder = lock_holder_;
  return out;
}

}  // namespace skillbus::wm
