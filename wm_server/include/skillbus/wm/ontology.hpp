// Concepts and relation types with their subclass and subproperty hierarchies, the
// ranges of data properties, and abstract (concept-level) relations, loaded from
// OWL/Turtle. Names are compact IRIs ("skiros:Product").
//
// Abstract relations come from OWL restrictions as SkiROS2's ontology states them,
//   skiros:Location rdfs:subClassOf [ owl:onProperty skiros:contain ; owl:someValuesFrom skiros:Product ]
// or from a plain triple between two classes (skiros:Location skiros:contain skiros:Product).
// may_relate(A, p, B) holds when some stated (C, q, D) has A ⊑ C, B ⊑ D and q ⊑ p.
#pragma once

#include <map>
#include <set>
#include <string>
#include <tuple>
#include <vector>

#include "skillbus/wm/rdf.hpp"

namespace skillbus::wm {

class Ontology {
 public:
  void add_class(const std::string& c);
  void add_subclass(const std::string& c, const std::string& parent);
  void add_relation_type(const std::string& p);
  void add_subproperty(const std::string& p, const std::string& parent);
  void add_data_property(const std::string& p, const std::string& range_xsd);  // "float", "int", ...
  void add_abstract_relation(const std::string& c, const std::string& p, const std::string& d);

  // Reads classes, object and datatype properties, subclass/subproperty axioms, ranges
  // and restrictions from triples (compacted with `prefixes`).
  void add_triples(const std::vector<Triple>& triples, const Prefixes& prefixes);
  void load_turtle(const std::string& text, Prefixes& prefixes, const std::string& source);
  // Turtle or RDF/XML (told apart by the text: OWL files are usually RDF/XML).
  void load(const std::string& text, Prefixes& prefixes, const std::string& source, const std::string& base_iri);
  // owl:imports of what was loaded that no loaded file declares as its owl:Ontology.
  std::vector<std::string> missing_imports() const;

  bool is_class(const std::string& c) const { return parents_.count(c) > 0; }
  bool is_relation(const std::string& p) const { return super_props_.count(p) > 0; }
  bool is_subclass(const std::string& c, const std::string& ancestor) const;  // reflexive
  bool is_subproperty(const std::string& p, const std::string& ancestor) const;
  const std::set<std::string>& subclasses(const std::string& c) const;  // c and below; empty if unknown
  bool may_relate(const std::string& subject_concept, const std::string& p, const std::string& object_concept) const;
  // "float", "int", "string", "bool", or "" when the ontology does not say.
  std::string data_range(const std::string& property) const;
  size_t class_count() const { return parents_.size(); }
  // Every class with its direct superclasses; every relation type with its direct
  // superproperties (the hierarchy the world model judges by).
  const std::map<std::string, std::set<std::string>>& class_parents() const { return parents_; }
  const std::map<std::string, std::set<std::string>>& relation_parents() const { return super_props_; }

 private:
  std::map<std::string, std::set<std::string>> parents_;      // class -> direct superclasses
  std::map<std::string, std::set<std::string>> super_props_;  // relation -> direct superproperties
  std::map<std::string, std::string> ranges_;
  std::vector<std::tuple<std::string, std::string, std::string>> abstract_;
  mutable std::map<std::string, std::set<std::string>> sub_cache_;
  std::set<std::string> ontologies_;  // owl:Ontology IRIs loaded (ontology_iri form)
  std::set<std::string> imports_;     // owl:imports of them
};

// An ontology's IRI without a trailing '#' or '/': "…/skiros.owl#" and "…/skiros.owl" are
// the same ontology.
std::string ontology_iri(const std::string& iri);

}  // namespace skillbus::wm
