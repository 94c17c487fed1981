#include "skillbus/wm/scene.hpp"

#include <cerrno>
#include <charconv>
#include <cmath>
#include <cstdlib>
#include <map>
#include <set>

namespace skillbus::wm {

namespace {

Value literal_value(const Term& t, const std::string& where) {
  const std::string dt = t.datatype.empty() ? "" : t.datatype.substr(t.datatype.find('#') + 1);
  const char* s = t.value.c_str();
  char* end = nullptr;
  // A scene's values are checked as a commit's are (convert.cpp): a NaN, an infinity or a
  // number beyond the type's range is refused, naming it, never stored (stored, it reached
  // every replica: the manager's then refused every read of the world, failing each task).
  if (dt == "float" || dt == "double" || dt == "decimal") {
    const double d = std::strtod(s, &end);
    if (end == s || *end) throw WmError(where + ": '" + t.value + "' is not a number");
    if (!std::isfinite(d))  // (NaN, inf, and an overflow: HUGE_VAL)
      throw WmError(where + ": '" + t.value + "' is not a finite number");
    return d;
  }
  if (dt == "int" || dt == "integer" || dt == "long" || dt == "short") {
    errno = 0;
    const long long i = std::strtoll(s, &end, 10);
    if (end == s || *end) throw WmError(where + ": '" + t.value + "' is not an integer");
    if (errno == ERANGE) throw WmError(where + ": '" + t.value + "' is beyond a 64-bit integer");
    return static_cast<int64_t>(i);
  }
  if (dt == "boolean") {
    if (t.value == "true" || t.value == "1") return true;
    if (t.value == "false" || t.value == "0") return false;
    throw WmError(where + ": '" + t.value + "' is not a boolean");
  }
  return t.value;
}

Term literal_term(const Value& v) {
  Term t;
  t.kind = Term::Literal;
  if (auto s = std::get_if<std::string>(&v)) {
    t.value = *s;
    t.datatype = std::string(kXsd) + "string";
  } else if (auto i = std::get_if<int64_t>(&v)) {
    t.value = std::to_string(*i);
    t.datatype = std::string(kXsd) + "int";
  } else if (auto d = std::get_if<double>(&v)) {
    char buf[64];
    const auto r = std::to_chars(buf, buf + sizeof buf, *d);  // shortest text that reads back exactly
    t.value.assign(buf, r.ptr);
    t.datatype = std::string(kXsd) + "float";
  } else {
    t.value = std::get<bool>(v) ? "true" : "false";
    t.datatype = std::string(kXsd) + "boolean";
  }
  return t;
}

Term iri(const std::string& s) { return Term{Term::Iri, s, "", ""}; }

}  // namespace

Scene read_scene(const std::string& turtle, Ontology& ontology, Prefixes& px, const std::string& source) {
  const std::vector<Triple> triples = parse_turtle(turtle, px, source);
  ontology.add_triples(triples, px);
  std::set<std::string> individuals;
  for (const auto& t : triples)
    if (t.p.value == kRdfType && t.o.value == kOwlNamedIndividual && t.s.kind == Term::Iri)
      individuals.insert(t.s.value);
  std::map<std::string, Element> elements;
  for (const auto& i : individuals) elements[i].id = px.compact(i);
  Scene scene;
  for (const auto& t : triples) {
    if (t.s.kind != Term::Iri || !individuals.count(t.s.value)) {
      scene.extra.push_back(t);  // class axioms, the ontology header, templates: kept as they are
      continue;
    }
    Element& e = elements[t.s.value];
    const std::string key = px.compact(t.p.value);
    if (t.p.value == kRdfType) {
      if (t.o.value == kOwlNamedIndividual) continue;
      if (!e.type.empty() && e.type != px.compact(t.o.value)) {
        scene.notes.push_back(e.id + ": second type " + px.compact(t.o.value) + " kept aside (its type is " + e.type +
                              ")");
        scene.extra.push_back(t);
      } else
        e.type = px.compact(t.o.value);
    } else if (t.p.value == kRdfsLabel && t.o.kind == Term::Literal) {
      e.label = t.o.value;
    } else if (t.o.kind == Term::Literal) {
      e.properties[key].push_back(literal_value(t.o, source + ", " + e.id + " " + key));
    } else if (t.o.kind == Term::Iri && individuals.count(t.o.value)) {
      scene.relations.push_back(Relation{e.id, key, px.compact(t.o.value)});
    } else {  // to an IRI that is no individual of this scene (a template, a class): kept as it is
      scene.extra.push_back(t);
    }
  }
  for (auto& [iri, e] : elements) scene.elements.push_back(std::move(e));
  return scene;
}

void check_scene_types(const Scene& scene, const Ontology& onto, const std::string& source) {
  std::map<std::string, std::vector<std::string>> unknown;
  for (const auto& e : scene.elements)
    if (!e.type.empty() && !onto.is_class(e.type)) unknown[e.type].push_back(e.id);
  if (unknown.empty()) return;
  std::string list;
  for (const auto& [type, ids] : unknown) {
    list += (list.empty() ? "" : ", ") + type + " (" + ids[0];
    if (ids.size() > 1) list += ids.size() == 2 ? ", " + ids[1] : " and " + std::to_string(ids.size() - 1) + " more";
    list += ")";
  }
  throw WmError(source + ": " + std::to_string(unknown.size()) + " type(s) that are not concepts of the loaded "
                "ontology: " + list + "; load the ontology that defines them (wm_server --ontology FILE..., or an "
                "owl:imports of the scene)");
}

std::vector<Triple> scene_triples(const WorldStore& store, const Prefixes& px, const std::vector<Triple>& extra) {
  std::vector<Triple> out;
  std::map<std::string, std::vector<const Relation*>> by_subject;
  const std::vector<Relation> relations = store.all_relations();
  for (const auto& r : relations) by_subject[r.subject].push_back(&r);
  for (const auto& [id, e] : store.elements()) {
    const Term s = iri(px.expand(id));
    out.push_back({s, iri(kRdfType), iri(px.expand(e.type))});
    out.push_back({s, iri(kRdfType), iri(kOwlNamedIndividual)});
    out.push_back({s, iri(kRdfsLabel), Term{Term::Literal, e.label, "", ""}});  // (SkiROS2 writes "" too)
    for (const auto& [key, values] : e.properties)
      for (const auto& v : values) out.push_back({s, iri(px.expand(key)), literal_term(v)});
    for (const Relation* r : by_subject[id]) out.push_back({s, iri(px.expand(r->predicate)), iri(px.expand(r->object))});
  }
  out.insert(out.end(), extra.begin(), extra.end());
  return out;
}

std::string write_scene(const WorldStore& store, const Prefixes& px, const std::vector<Triple>& extra) {
  return write_turtle(scene_triples(store, px, extra), px);
}

}  // namespace skillbus::wm
