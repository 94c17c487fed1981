// The world itself: elements and relations with indexes, transactions that apply all
// or nothing, queries, and the version that counts committed transactions.
//
// Elements and relations are held as immutable shared objects (an update replaces the
// element, it never changes it in place). That makes an image of the whole world cheap
// to take: a vector of pointers, no copy of any string (image(), for snapshots written in
// the background while commits go on), and lets the indexes point at the objects
// instead of keeping copies of their strings.
#pragma once

#include <functional>
#include <map>
#include <memory>
#include <set>
#include <string>
#include <string_view>
#include <utility>
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

// A page of a query's result (in id order): the matches whose id sorts after `after`,
// `offset` of them skipped, at most `limit` (0: all).
struct Page {
  std::string after;
  long offset = 0;
  long limit = 0;
};

struct TxnResult {
  int64_t version = 0;
  std::vector<std::string> ids;  // of added elements, in order
  std::vector<Op> effect;        // what changed, elements in their state after the commit
};

using ElementPtr = std::shared_ptr<const Element>;
using RelationPtr = std::shared_ptr<const Relation>;

// The world at one version, immutable: it shares the elements and relations with the
// store (which never changes them, it replaces them), so taking it copies pointers only.
struct WorldImage {
  int64_t version = 0;
  int64_t next_id = 1;
  std::vector<ElementPtr> elements;    // in id order
  std::vector<RelationPtr> relations;  // in (subject, predicate, object) order
};

// The elements by id, read-only, iterated as pairs (id, element) in id order.
class ElementsView {
 public:
  using Map = std::map<std::string, ElementPtr, std::less<>>;
  class iterator {
   public:
    using value_type = std::pair<const std::string&, const Element&>;
    explicit iterator(Map::const_iterator it) : it_(it) {}
    value_type operator*() const { return {it_->first, *it_->second}; }
    iterator& operator++() { ++it_; return *this; }
    bool operator==(const iterator& o) const { return it_ == o.it_; }
    bool operator!=(const iterator& o) const { return it_ != o.it_; }
    const Element& element() const { return *it_->second; }
   private:
    Map::const_iterator it_;
  };
  explicit ElementsView(const Map& m) : m_(&m) {}
  iterator begin() const { return iterator(m_->begin()); }
  iterator end() const { return iterator(m_->end()); }
  iterator upper_bound(std::string_view id) const { return iterator(m_->upper_bound(id)); }
  size_t size() const { return m_->size(); }
  bool empty() const { return m_->empty(); }
  size_t count(std::string_view id) const { return m_->count(id); }
  bool operator==(const ElementsView& o) const;  // the same ids with equal elements
 private:
  const Map* m_;
};

class WorldStore {
 public:
  explicit WorldStore(const Ontology& ontology) : ontology_(ontology) {}

  // Validates and applies `ops` atomically; throws WmError naming the first problem and
  // leaves the world as it was. expected_version >= 0 must equal the current version.
  TxnResult apply(const std::vector<Op>& ops, int64_t expected_version = -1);
  // Takes back the last applied transaction (used when it cannot be made durable).
  void undo_last();

  // Valid until the element is updated or removed.
  const Element* get(const std::string& id) const;
  // Sorted by id; with a page, only that page (found without looking at the matches
  // before it, so that paging through a large result costs no more than reading it).
  std::vector<const Element*> query(const Query& q, const Page& page = {}) const;
  std::vector<Relation> relations_touching(const std::vector<const Element*>& elements) const;  // sorted
  std::vector<Relation> relations_to(const std::vector<const Element*>& objects) const;        // sorted
  // Relations matching a pattern ("" = any; p matches its subproperties too).
  std::vector<Relation> relations(const std::string& s, const std::string& p, const std::string& o) const;
  ElementsView elements() const { return ElementsView(elements_); }
  std::vector<Relation> all_relations() const;  // sorted
  size_t relation_count() const { return relations_.size(); }
  WorldImage image() const;

  int64_t version() const { return version_; }
  int64_t next_id() const { return next_id_; }
  // Replaces the whole world (snapshot restore, scene load).
  void reset(std::vector<Element> elements, std::vector<Relation> relations, int64_t version, int64_t next_id);
  // Restores a snapshot piece by piece (no vector of every element in between): clear(),
  // then insert_element() and insert_relation() (unchecked: a snapshot holds a checked
  // world), then set_version().
  void clear();
  void insert_element(Element e);
  void insert_relation(Relation r);
  void set_version(int64_t version, int64_t next_id);
  const Ontology& ontology() const { return ontology_; }

 private:
  struct ByValue {
    using is_transparent = void;
    bool operator()(const RelationPtr& a, const RelationPtr& b) const { return *a < *b; }
    bool operator()(const RelationPtr& a, const Relation& b) const { return *a < b; }
    bool operator()(const Relation& a, const RelationPtr& b) const { return a < *b; }
  };
  using RelationSet = std::set<RelationPtr, ByValue>;
  // Ids in an index are views of the id of the element in elements_ (which outlives its
  // entries: an element leaves the indexes before it is released).
  using IdSet = std::set<std::string_view>;

  void check_element(const Element& e) const;
  // After a transaction's operations: each element it put into a container (skiros:contain
  // or a subproperty) has that one container and is not its own ancestor. The containment
  // is the frame tree (transforms.hpp): a second container or a cycle has no pose.
  void check_containment(const std::vector<Op>& effect) const;
  void index(const Element& e);
  void unindex(const Element& e);
  void put(ElementPtr e);
  void erase(const std::string& id);
  void bump_next_id(const std::string& id);
  void insert_rel(RelationPtr r);
  void erase_rel(const Relation& r);
  const RelationSet& relations_of(const std::string& id) const;  // as subject or object

  const Ontology& ontology_;
  ElementsView::Map elements_;
  std::map<std::string, IdSet, std::less<>> by_type_;
  std::map<std::string, IdSet, std::less<>> by_label_;
  RelationSet relations_;
  std::map<std::string, RelationSet, std::less<>> rel_by_node_;  // subject or object -> relations
  int64_t version_ = 0;
  int64_t next_id_ = 1;
  std::vector<std::function<void()>> undo_;  // of the last transaction, to run in reverse
  int64_t undo_next_id_ = 1;
};

}  // namespace skillbus::wm
