#include "skillbus/wm/ontology.hpp"

#include <deque>

#include "skillbus/wm/model.hpp"

namespace skillbus::wm {

void Ontology::add_class(const std::string& c) {
  parents_[c];
  sub_cache_.clear();
}

void Ontology::add_subclass(const std::string& c, const std::string& parent) {
  parents_[c].insert(parent);
  parents_[parent];
  sub_cache_.clear();
}

void Ontology::add_relation_type(const std::string& p) { super_props_[p]; }

void Ontology::add_subproperty(const std::string& p, const std::string& parent) {
  super_props_[p].insert(parent);
  super_props_[parent];
}

void Ontology::add_data_property(const std::string& p, const std::string& range) { ranges_[p] = range; }

void Ontology::add_abstract_relation(const std::string& c, const std::string& p, const std::string& d) {
  abstract_.emplace_back(c, p, d);
}

namespace {

bool reaches(const std::map<std::string, std::set<std::string>>& up, const std::string& from, const std::string& to) {
  std::deque<std::string> todo{from};
  std::set<std::string> seen;
  while (!todo.empty()) {
    std::string x = todo.front();
    todo.pop_front();
    if (x == to) return true;
    if (!seen.insert(x).second) continue;
    auto it = up.find(x);
    if (it != up.end()) todo.insert(todo.end(), it->second.begin(), it->second.end());
  }
  return false;
}

std::string xsd_range(const std::string& iri) {
  const std::string local = iri.substr(iri.find('#') + 1);
  if (local == "float" || local == "double" || local == "decimal") return "float";
  if (local == "int" || local == "integer" || local == "long" || local == "short") return "int";
  if (local == "boolean") return "bool";
  if (local == "string") return "string";
  return "";
}

}  // namespace

bool Ontology::is_subclass(const std::string& c, const std::string& ancestor) const { return reaches(parents_, c, ancestor); }

bool Ontology::is_subproperty(const std::string& p, const std::string& ancestor) const {
  return reaches(super_props_, p, ancestor);
}

const std::set<std::string>& Ontology::subclasses(const std::string& c) const {
  auto it = sub_cache_.find(c);
  if (it != sub_cache_.end()) return it->second;
  std::set<std::string>& out = sub_cache_[c];
  if (!is_class(c)) return out;
  for (const auto& [cls, ups] : parents_)
    if (is_subclass(cls, c)) out.insert(cls);
  return out;
}

bool Ontology::may_relate(const std::string& s, const std::string& p, const std::string& o) const {
  for (const auto& [c, q, d] : abstract_)
    if (is_subclass(s, c) && is_subclass(o, d) && is_subproperty(q, p)) return true;
  return false;
}

std::string Ontology::data_range(const std::string& property) const {
  auto it = ranges_.find(property);
  return it == ranges_.end() ? "" : it->second;
}

void Ontology::add_triples(const std::vector<Triple>& triples, const Prefixes& px) {
  const std::string owl = "http://www.w3.org/2002/07/owl#";
  const std::string rdfs = "http://www.w3.org/2000/01/rdf-schema#";
  // Blank nodes that are restrictions: id -> (property, class)
  std::map<std::string, std::pair<std::string, std::string>> restriction;
  std::set<std::string> classes, object_props, data_props;
  for (const auto& t : triples) {
    const std::string& p = t.p.value;
    if (t.s.kind == Term::Blank) {
      if (p == owl + "onProperty") restriction[t.s.value].first = px.compact(t.o.value);
      if (p == owl + "someValuesFrom" || p == owl + "allValuesFrom")
        restriction[t.s.value].second = px.compact(t.o.value);
      continue;
    }
    if (p == owl + "imports" && t.o.kind == Term::Iri) imports_.insert(ontology_iri(t.o.value));
    if (p == kRdfType && t.o.value == owl + "Ontology") ontologies_.insert(ontology_iri(t.s.value));
    if (p == kRdfType) {
      if (t.o.value == kOwlClass || t.o.value == rdfs + "Class" || t.o.value == owl + "class")
        classes.insert(px.compact(t.s.value));
      if (t.o.value == owl + "ObjectProperty") object_props.insert(px.compact(t.s.value));
      if (t.o.value == owl + "DatatypeProperty") data_props.insert(px.compact(t.s.value));
    }
  }
  for (const auto& c : classes) add_class(c);
  for (const auto& p : object_props) add_relation_type(p);
  for (const auto& t : triples) {
    if (t.s.kind == Term::Blank) continue;
    const std::string s = px.compact(t.s.value), p = t.p.value;
    if (p == kRdfsSubClassOf) {
      if (t.o.kind == Term::Blank) {
        auto r = restriction.find(t.o.value);
        if (r != restriction.end() && !r->second.first.empty() && !r->second.second.empty())
          add_abstract_relation(s, r->second.first, r->second.second);
      } else {
        add_subclass(s, px.compact(t.o.value));
      }
    } else if (p == kRdfsSubPropertyOf && t.o.kind == Term::Iri) {
      if (data_props.count(s)) continue;
      add_subproperty(s, px.compact(t.o.value));
    } else if (p == kRdfsRange && data_props.count(s) && t.o.kind == Term::Iri) {
      const std::string r = xsd_range(t.o.value);
      if (!r.empty()) add_data_property(s, r);
    } else if (t.o.kind == Term::Iri && is_class(s) && is_class(px.compact(t.o.value)) &&
               is_relation(px.compact(p))) {
      add_abstract_relation(s, px.compact(p), px.compact(t.o.value));  // plain class-level triple
    }
  }
}

void Ontology::load_turtle(const std::string& text, Prefixes& prefixes, const std::string& source) {
  add_triples(parse_turtle(text, prefixes, source), prefixes);
}

void Ontology::load(const std::string& text, Prefixes& prefixes, const std::string& source,
                    const std::string& base_iri) {
  add_triples(parse_rdf(text, prefixes, source, base_iri), prefixes);
}

std::vector<std::string> Ontology::missing_imports() const {
  std::vector<std::string> out;
  for (const auto& i : imports_)
    if (!ontologies_.count(i)) out.push_back(i);
  return out;
}

std::string ontology_iri(const std::string& iri) {
  std::string s = iri;
  while (!s.empty() && (s.back() == '#' || s.back() == '/')) s.pop_back();
  return s;
}

}  // namespace skillbus::wm
