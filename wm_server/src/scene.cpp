#include "skillbus/wm/scene.hpp"

#include <charconv>
#include <cstdlib>
#include <map>
#include <set>

namespace skillbus::wm {

namespace {

Value literal_value(const Term& t, const std::string& where) {
  const std::string dt = t.datatype.empty() ? "" : t.datatype.substr(t.datatype.find('#') + 1);
  const char* s = t.value.c_str();
  char* end = nullptr;
  if (dt == "float" || dt == "double" || dt == "decimal") {
    const double d = std::strtod(s, &end);
    if (end == s || *end) throw WmError(where + ": '" + t.value + "' is not a number");
    return d;
  }
  if (dt == "int" || dt == "integer" || dt == "long" || dt == "short") {
    const long long i = std::strtoll(s, &end, 10);
    if (end == s || *end) throw WmError(where + ": '" + t.value + "' is not an integer");
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
    if (t.s.kind != Term::Iri || !individuals.count(t.s.value)) continue;
    Element& e = elements[t.s.value];
    const std::string key = px.compact(t.p.value);
    if (t.p.value == kRdfType) {
      if (t.o.value == kOwlNamedIndividual) continue;
      if (!e.type.empty() && e.type != px.compact(t.o.value))
        scene.notes.push_back(e.id + ": second type " + px.compact(t.o.value) + " ignored (kept " + e.type + ")");
      else
        e.type = px.compact(t.o.value);
    } else if (t.p.value == kRdfsLabel && t.o.kind == Term::Literal) {
      e.label = t.o.value;
    } else if (t.o.kind == Term::Literal) {
      e.properties[key].push_back(literal_value(t.o, source + ", " + e.id + " " + key));
    } else if (t.o.kind == Term::Iri && individuals.count(t.o.value)) {
      scene.relations.push_back(Relation{e.id, key, px.compact(t.o.value)});
    } else {
      scene.notes.push_back("skipped " + e.id + " " + key + " " + px.compact(t.o.value) +
                            ": the object is not an individual of this scene");
    }
  }
  for (auto& [iri, e] : elements) scene.elements.push_back(std::move(e));
  return scene;
}

std::string write_scene(const WorldStore& store, const Prefixes& px) {
  std::vector<Triple> out;
  std::map<std::string, std::vector<const Relation*>> by_subject;
  const std::vector<Relation> relations = store.all_relations();
  for (const auto& r : relations) by_subject[r.subject].push_back(&r);
  for (const auto& [id, e] : store.elements()) {
    const Term s = iri(px.expand(id));
    out.push_back({s, iri(kRdfType), iri(px.expand(e.type))});
    out.push_back({s, iri(kRdfType), iri(kOwlNamedIndividual)});
    out.push_back({s, iri(kRdfsLabel), Term{Term::Literal, e.label, "", ""}});
    for (const auto& [key, values] : e.properties)
      for (const auto& v : values) out.push_back({s, iri(px.expand(key)), literal_term(v)});
    for (const Relation* r : by_subject[id]) out.push_back({s, iri(px.expand(r->predicate)), iri(px.expand(r->object))});
  }
  return write_turtle(out, px);
}

}  // namespace skillbus::wm
