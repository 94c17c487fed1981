#include "skillbus/wm/store.hpp"

#include <algorithm>
#include <set>

namespace skillbus::wm {

const char* value_type_name(const Value& v) {
  static const char* names[] = {"string", "int", "float", "bool"};
  return names[v.index()];
}

namespace {

std::string rel_text(const Relation& r) { return "(" + r.subject + " " + r.predicate + " " + r.object + ")"; }

// What differs between an element as read and as it is now, for the refusal of a stale edit.
std::string what_changed(const Element& read, const Element& now) {
  std::string out;
  auto add = [&out](const std::string& what) { out += (out.empty() ? "" : ", ") + what; };
  if (read.type != now.type) add("type " + read.type + " -> " + now.type);
  if (read.label != now.label) add("label '" + read.label + "' -> '" + now.label + "'");
  for (const auto& [key, values] : now.properties) {
    auto it = read.properties.find(key);
    if (it == read.properties.end()) add(key + " added");
    else if (it->second != values) add(key);
  }
  for (const auto& [key, values] : read.properties)
    if (!now.properties.count(key)) add(key + " removed");
  return out;
}

// "skiros:Cube-12" -> 12, or -1 when the id does not end in -N.
int64_t id_number(const std::string& id) {
  const auto dash = id.rfind('-');
  if (dash == std::string::npos || dash + 1 >= id.size()) return -1;
  int64_t n = 0;
  for (size_t i = dash + 1; i < id.size(); ++i) {
    if (id[i] < '0' || id[i] > '9' || n > (INT64_MAX - 9) / 10) return -1;
    n = n * 10 + (id[i] - '0');
  }
  return n;
}

}  // namespace

bool ElementsView::operator==(const ElementsView& o) const {
  if (m_->size() != o.m_->size()) return false;
  for (auto a = m_->begin(), b = o.m_->begin(); a != m_->end(); ++a, ++b)
    if (a->first != b->first || !(*a->second == *b->second)) return false;
  return true;
}

namespace {

// A NUL inside a string cannot be sent: LCM writes strings up to their first NUL, so a
// stored one would make every reply that carries it undecodable (from a Turtle scene's
// "\u0000" too, not only from a message).
bool has_nul(const std::string& s) { return s.find('\0') != std::string::npos; }

}  // namespace

void WorldStore::check_element(const Element& e) const {
  if (has_nul(e.id) || has_nul(e.type) || has_nul(e.label))
    throw WmError("element " + e.id.substr(0, e.id.find('\0')) + ": a NUL character in its id, type or label");
  for (const auto& [key, values] : e.properties) {
    bool nul = has_nul(key);
    for (const auto& v : values)
      if (const auto* text = std::get_if<std::string>(&v)) nul = nul || has_nul(*text);
    if (nul) throw WmError("property " + key.substr(0, key.find('\0')) + " of " + e.id + ": a NUL character");
  }
  if (e.id.empty() || e.id.find_first_of(" \t\n<>\"") != std::string::npos)
    throw WmError("bad element id '" + e.id + "' (want prefix:Name, no spaces)");
  if (e.type.empty()) throw WmError("element " + e.id + " has no type");
  if (!ontology_.is_class(e.type))
    throw WmError("unknown type '" + e.type + "' for element " + e.id + " (not a concept of the ontology)");
  for (const auto& [key, values] : e.properties) {
    if (key.empty()) throw WmError("element " + e.id + " has a property without a key");
    const std::string range = ontology_.data_range(key);
    if (range.empty()) continue;
    for (const auto& v : values)
      if (range != value_type_name(v))
        throw WmError("property " + key + " of " + e.id + " must be " + range + ", got " + value_type_name(v));
  }
}

void WorldStore::check_containment(const std::vector<Op>& effect) const {
  static const std::string kContain = "skiros:contain";
  auto containers = [&](const std::string& id) {
    std::vector<std::string> out;
    for (const auto& r : relations_of(id))
      if (r->object == id && ontology_.is_subproperty(r->predicate, kContain)) out.push_back(r->subject);
    return out;
  };
  for (const Op& op : effect) {
    if (op.kind != Op::AddRelation || !ontology_.is_subproperty(op.relation.predicate, kContain)) continue;
    const std::string& child = op.relation.object;
    const auto in = containers(child);
    if (in.size() > 1)
      throw WmError("element " + child + " would be in two containers, " + in[0] + " and " + in[1] +
                    " (remove it from the old one in the same transaction)");
    std::string path = child, cur = child;
    std::set<std::string> seen{child};
    for (auto up = containers(cur); up.size() == 1; up = containers(cur)) {
      cur = up[0];
      path = cur + " contains " + path;
      if (!seen.insert(cur).second) throw WmError("containment cycle: " + path);
    }
  }
}

void WorldStore::index(const Element& e) {
  by_type_[e.type].insert(e.id);
  by_label_[e.label].insert(e.id);
}

void WorldStore::unindex(const Element& e) {
  for (auto* index : {&by_type_, &by_label_}) {
    auto it = index->find(index == &by_type_ ? e.type : e.label);
    if (it == index->end()) continue;
    it->second.erase(e.id);
    if (it->second.empty()) index->erase(it);  // no empty sets left behind by churn
  }
}

void WorldStore::put(ElementPtr e) {
  auto it = elements_.find(e->id);
  if (it == elements_.end()) {
    index(*e);
    const std::string id = e->id;
    elements_.emplace(id, std::move(e));
    return;
  }
  unindex(*it->second);  // before the old element (whose id the index views) is released
  index(*e);
  it->second = std::move(e);
}

void WorldStore::erase(const std::string& id) {
  auto it = elements_.find(id);
  if (it == elements_.end()) return;
  unindex(*it->second);
  elements_.erase(it);
}

void WorldStore::bump_next_id(const std::string& id) {
  const int64_t n = id_number(id);
  if (n >= next_id_) next_id_ = n + 1;
}

void WorldStore::insert_rel(RelationPtr r) {
  rel_by_node_[r->subject].insert(r);
  rel_by_node_[r->object].insert(r);
  relations_.insert(std::move(r));
}

void WorldStore::erase_rel(const Relation& r) {
  for (const std::string* node : {&r.subject, &r.object}) {
    auto it = rel_by_node_.find(*node);
    if (it == rel_by_node_.end()) continue;
    auto found = it->second.find(r);  // (a set erases by an equivalent key only from C++23)
    if (found != it->second.end()) it->second.erase(found);
    if (it->second.empty()) rel_by_node_.erase(it);
  }
  auto found = relations_.find(r);
  if (found != relations_.end()) relations_.erase(found);
}

TxnResult WorldStore::apply(const std::vector<Op>& ops, int64_t expected_version) {
  if (expected_version >= 0 && expected_version != version_)
    throw WmError("version conflict: the transaction expects version " + std::to_string(expected_version) +
                  ", the world is at " + std::to_string(version_));
  if (ops.empty()) throw WmError("a transaction needs at least one operation");
  undo_.clear();
  undo_next_id_ = next_id_;
  TxnResult result;
  try {
    for (size_t i = 0; i < ops.size(); ++i) {
      const Op& op = ops[i];
      const std::string where = "operation " + std::to_string(i + 1) + ": ";
      try {
        switch (op.kind) {
          case Op::AddElement: {
            Element e = op.element;
            if (e.id.empty()) {
              if (e.type.empty()) throw WmError("a new element needs a type");
              e.id = e.type + "-" + std::to_string(next_id_);
            }
            if (elements_.count(e.id)) throw WmError("element " + e.id + " exists already");
            check_element(e);
            const int64_t before = next_id_;
            bump_next_id(e.id);
            if (next_id_ == before) ++next_id_;  // every add consumes a number, as in SkiROS2
            auto added = std::make_shared<const Element>(std::move(e));
            put(added);
            const std::string& id = added->id;
            undo_.push_back([this, id] { erase(id); });
            result.ids.push_back(id);
            result.effect.push_back(Op{Op::AddElement, *added, {}});
            break;
          }
          case Op::UpdateElement: {
            auto it = elements_.find(op.element.id);
            if (it == elements_.end()) throw WmError("no element " + op.element.id + " to update");
            check_element(op.element);
            ElementPtr old = it->second;
            put(std::make_shared<const Element>(op.element));
            undo_.push_back([this, old] { put(old); });
            result.effect.push_back(Op{Op::UpdateElement, op.element, {}});
            break;
          }
          case Op::RemoveElement: {
            auto it = elements_.find(op.element.id);
            if (it == elements_.end()) throw WmError("no element " + op.element.id + " to remove");
            ElementPtr old = it->second;
            const RelationSet touching = relations_of(old->id);
            for (const auto& r : touching) {
              erase_rel(*r);
              undo_.push_back([this, r] { insert_rel(r); });
              result.effect.push_back(Op{Op::RemoveRelation, {}, *r});
            }
            erase(old->id);
            undo_.push_back([this, old] { put(old); });
            result.effect.push_back(Op{Op::RemoveElement, Element{old->id, old->type, old->label, {}}, {}});
            break;
          }
          case Op::AddRelation: {
            const Relation& r = op.relation;
            if (!elements_.count(r.subject)) throw WmError("relation " + rel_text(r) + ": no element " + r.subject);
            if (!elements_.count(r.object)) throw WmError("relation " + rel_text(r) + ": no element " + r.object);
            if (!ontology_.is_relation(r.predicate))
              throw WmError("relation " + rel_text(r) + ": unknown relation type " + r.predicate);
            if (relations_.count(r)) break;  // already there: nothing changes
            insert_rel(std::make_shared<const Relation>(r));
            undo_.push_back([this, r] { erase_rel(r); });
            result.effect.push_back(Op{Op::AddRelation, {}, r});
            break;
          }
          case Op::RemoveRelation: {
            auto found = relations_.find(op.relation);
            if (found == relations_.end()) throw WmError("no relation " + rel_text(op.relation) + " to remove");
            RelationPtr r = *found;
            erase_rel(*r);
            undo_.push_back([this, r] { insert_rel(r); });
            result.effect.push_back(Op{Op::RemoveRelation, {}, *r});
            break;
          }
          case Op::ExpectElement: {
            const Element* now = get(op.element.id);
            if (!now) throw WmError("element " + op.element.id + " was removed since it was read");
            if (!(*now == op.element))
              throw WmError("element " + op.element.id + " changed since it was read (" +
                            what_changed(op.element, *now) + "): read it again");
            break;
          }
          default:
            throw WmError("unknown operation kind " + std::to_string(static_cast<int>(op.kind)));
        }
      } catch (const WmError& e) {
        throw WmError(where + e.what());
      }
    }
    check_containment(result.effect);
  } catch (...) {
    for (auto it = undo_.rbegin(); it != undo_.rend(); ++it) (*it)();
    undo_.clear();
    next_id_ = undo_next_id_;
    throw;
  }
  result.version = ++version_;
  return result;
}

void WorldStore::undo_last() {
  for (auto it = undo_.rbegin(); it != undo_.rend(); ++it) (*it)();
  undo_.clear();
  next_id_ = undo_next_id_;
  --version_;
}

const Element* WorldStore::get(const std::string& id) const {
  auto it = elements_.find(id);
  return it == elements_.end() ? nullptr : it->second.get();
}

namespace {

// Merges sorted id sets from `after` on, in id order, without duplicates: the candidates
// of a query by type (one set per subclass) page by page.
class IdMerge {
 public:
  void add(const std::set<std::string_view>& ids, std::string_view after) {
    auto it = after.empty() ? ids.begin() : ids.upper_bound(after);
    if (it != ids.end()) heads_.push_back({it, ids.end()});
  }
  bool next(std::string_view& out) {
    size_t best = heads_.size();
    for (size_t i = 0; i < heads_.size(); ++i)
      if (best == heads_.size() || *heads_[i].first < *heads_[best].first) best = i;
    if (best == heads_.size()) return false;
    out = *heads_[best].first;
    for (auto& h : heads_)  // an id in several sets (it cannot be, but cheaply safe)
      while (h.first != h.second && *h.first == out) ++h.first;
    heads_.erase(std::remove_if(heads_.begin(), heads_.end(), [](const auto& h) { return h.first == h.second; }),
                 heads_.end());
    return true;
  }

 private:
  using It = std::set<std::string_view>::const_iterator;
  std::vector<std::pair<It, It>> heads_;
};

}  // namespace

std::vector<const Element*> WorldStore::query(const Query& q, const Page& page) const {
  // The candidates in id order, from page.after on: from the ids asked for, the type
  // index (merged over the subclasses), the label index, or every element.
  IdMerge merge;
  std::vector<std::string> ids;
  if (!q.ids.empty()) {
    ids = q.ids;
    std::sort(ids.begin(), ids.end());
    ids.erase(std::unique(ids.begin(), ids.end()), ids.end());
    if (!page.after.empty()) ids.erase(ids.begin(), std::upper_bound(ids.begin(), ids.end(), page.after));
  } else if (!q.type.empty()) {
    const std::set<std::string> one{q.type};
    for (const auto& t : q.exact_type ? one : ontology_.subclasses(q.type)) {
      auto it = by_type_.find(t);
      if (it != by_type_.end()) merge.add(it->second, page.after);
    }
  } else if (!q.label.empty()) {
    auto it = by_label_.find(q.label);
    if (it != by_label_.end()) merge.add(it->second, page.after);
  }
  const bool every = q.ids.empty() && q.type.empty() && q.label.empty();
  auto all_it = page.after.empty() ? elements_.begin() : elements_.upper_bound(page.after);
  size_t id_i = 0;
  auto next = [&]() -> const Element* {
    if (!q.ids.empty()) {
      while (id_i < ids.size()) {
        auto it = elements_.find(ids[id_i++]);
        if (it != elements_.end()) return it->second.get();
      }
      return nullptr;
    }
    if (every) return all_it == elements_.end() ? nullptr : (all_it++)->second.get();
    std::string_view id;
    return merge.next(id) ? elements_.find(id)->second.get() : nullptr;
  };
  std::vector<const Element*> out;
  long skipped = 0;
  while (const Element* found = next()) {
    const Element& e = *found;
    const std::string& id = e.id;
    if (!q.label.empty() && e.label != q.label) continue;
    if (!q.type.empty() && (q.exact_type ? e.type != q.type : !ontology_.is_subclass(e.type, q.type))) continue;
    bool ok = true;
    for (const auto& [key, want] : q.properties) {
      auto p = e.properties.find(key);
      if (p == e.properties.end()) { ok = false; break; }
      for (const auto& v : want)
        if (std::find(p->second.begin(), p->second.end(), v) == p->second.end()) ok = false;
    }
    for (const auto& pat : q.relations) {
      if (!ok) break;
      const std::string& s = pat.subject.empty() ? id : pat.subject;
      const std::string& o = pat.object.empty() ? id : pat.object;
      bool found_rel = false;
      for (const auto& r : relations_of(id))
        if ((s == "*" || r->subject == s) && (o == "*" || r->object == o) &&
            (pat.predicate.empty() || pat.predicate == "*" || ontology_.is_subproperty(r->predicate, pat.predicate)))
          found_rel = true;
      ok = found_rel;
    }
    if (!ok) continue;
    if (skipped < page.offset) {
      ++skipped;
      continue;
    }
    out.push_back(&e);
    if (page.limit > 0 && static_cast<long>(out.size()) >= page.limit) break;
  }
  return out;
}

std::vector<Relation> WorldStore::relations_touching(const std::vector<const Element*>& elements) const {
  std::set<const Relation*> seen;  // a relation between two of them once
  std::vector<Relation> out;
  for (const Element* e : elements)
    for (const auto& r : relations_of(e->id))
      if (seen.insert(r.get()).second) out.push_back(*r);
  std::sort(out.begin(), out.end());
  return out;
}

std::vector<Relation> WorldStore::relations_to(const std::vector<const Element*>& objects) const {
  std::vector<Relation> out;
  for (const Element* e : objects)
    for (const auto& r : relations_of(e->id))
      if (r->object == e->id) out.push_back(*r);
  std::sort(out.begin(), out.end());
  return out;
}

const WorldStore::RelationSet& WorldStore::relations_of(const std::string& id) const {
  static const RelationSet none;
  auto it = rel_by_node_.find(id);
  return it == rel_by_node_.end() ? none : it->second;
}

std::vector<Relation> WorldStore::relations(const std::string& s, const std::string& p, const std::string& o) const {
  std::vector<Relation> out;
  const RelationSet& pool = !s.empty() ? relations_of(s) : !o.empty() ? relations_of(o) : relations_;
  for (const auto& r : pool)
    if ((s.empty() || r->subject == s) && (o.empty() || r->object == o) &&
        (p.empty() || ontology_.is_subproperty(r->predicate, p)))
      out.push_back(*r);
  return out;
}

std::vector<Relation> WorldStore::all_relations() const {
  std::vector<Relation> out;
  out.reserve(relations_.size());
  for (const auto& r : relations_) out.push_back(*r);
  return out;
}

WorldImage WorldStore::image() const {
  WorldImage w;
  w.version = version_;
  w.next_id = next_id_;
  w.elements.reserve(elements_.size());
  for (const auto& [id, e] : elements_) w.elements.push_back(e);
  w.relations.assign(relations_.begin(), relations_.end());
  return w;
}

void WorldStore::clear() {
  elements_.clear();
  by_type_.clear();
  by_label_.clear();
  relations_.clear();
  rel_by_node_.clear();
  undo_.clear();
}

void WorldStore::insert_element(Element e) { put(std::make_shared<const Element>(std::move(e))); }

void WorldStore::insert_relation(Relation r) { insert_rel(std::make_shared<const Relation>(std::move(r))); }

void WorldStore::set_version(int64_t version, int64_t next_id) {
  version_ = version;
  next_id_ = next_id;
  for (const auto& [id, e] : elements_) bump_next_id(id);
}

void WorldStore::reset(std::vector<Element> elements, std::vector<Relation> relations, int64_t version,
                       int64_t next_id) {
  clear();
  for (auto& e : elements) insert_element(std::move(e));
  for (auto& r : relations) insert_relation(std::move(r));
  set_version(version, next_id);
}

}  // namespace skillbus::wm
