// The world itself: elements and relations with indexes, transactions that apply all
// or nothing, queries, and the version that counts committed transactions.
#pragma once

#include <functional>
#include <map>
#include <set>
#include <string>
#include <vector>

#include "skillbus/wm/model.hpp"
#include "skillbus/wm/ontology.hpp"

namespace skillbus::wm {

struct Query {
  std::vector<std::string> ids;
  std::string type;  // with subclasses unless exact_type
  bool exact_type = false;
  std::string label;
  std::map<std::string, std::vector<Value>> properties;
  std::vector<Relation> relations;  // "" = the element itself, "*" = any
};

struct TxnResult {
  int64_t version = 0;
  std::vector<std::string> ids;  // of added elements, in order
  std::vector<Op> effect;        // what changed, elements in their state after the commit
};

class WorldStore {
 public:
  explicit WorldStore(const Ontology& ontology) : ontology_(ontology) {}

  // Validates and applies `ops` atomically; throws WmError naming the first problem and
  // leaves the world as it was. expected_version >= 0 must equal the current version.
  TxnResult apply(const std::vector<Op>& ops, int64_t expected_version = -1);
  // Takes back the last applied transaction (used when it cannot be made durable).
  void undo_last();

  const Element* get(const std::string& id) const;
  std::vector<const Element*> query(const Query& q) const;  // sorted by id
  std::vector<Relation> relations_touching(const std::set<std::string>& ids) const;
  // Relations matching a pattern ("" = any; p matches its subproperties too).
  std::vector<Relation> relations(const std::string& s, const std::string& p, const std::string& o) const;
  const std::set<Relation>& relations_of(const std::string& id) const;  // as subject or object
  const std::map<std::string, Element>& elements() const { return elements_; }
  const std::set<Relation>& all_relations() const { return relations_; }

  int64_t version() const { return version_; }
  int64_t next_id() const { return next_id_; }
  // Replaces the whole world (snapshot restore, scene load).
  void reset(std::vector<Element> elements, std::vector<Relation> relations, int64_t version, int64_t next_id);
  const Ontology& ontology() const { return ontology_; }

 private:
  void check_element(const Element& e) const;
  void index(const Element& e);
  void unindex(const Element& e);
  void put(Element e);
  void erase(const std::string& id);
  void bump_next_id(const std::string& id);

  const Ontology& ontology_;
  std::map<std::string, Element> elements_;
  std::map<std::string, std::set<std::string>> by_type_;
  std::map<std::string, std::set<std::string>> by_label_;
  std::set<Relation> relations_;
  std::map<std::string, std::set<Relation>> rel_by_node_;  // subject or object -> relations
  int64_t version_ = 0;
  int64_t next_id_ = 1;
  std::vector<std::function<void()>> undo_;  // of the last transaction, to run in reverse
  int64_t undo_next_id_ = 1;
};

}  // namespace skillbus::wm
