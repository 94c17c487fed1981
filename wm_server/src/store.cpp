#include "skillbus/wm/store.hpp"

#include <algorithm>

namespace skillbus::wm {

const char* value_type_name(const Value& v) {
  static const char* names[] = {"string", "int", "float", "bool"};
  return names[v.index()];
}

namespace {

std::string rel_text(const Relation& r) { return "(" + r.subject + " " + r.predicate + " " + r.object + ")"; }

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

void WorldStore::check_element(const Element& e) const {
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

void WorldStore::index(const Element& e) {
  by_type_[e.type].insert(e.id);
  by_label_[e.label].insert(e.id);
}

void WorldStore::unindex(const Element& e) {
  by_type_[e.type].erase(e.id);
  by_label_[e.label].erase(e.id);
}

void WorldStore::put(Element e) {
  auto it = elements_.find(e.id);
  if (it != elements_.end()) unindex(it->second);
  index(e);
  const std::string id = e.id;
  elements_[id] = std::move(e);
}

void WorldStore::erase(const std::string& id) {
  auto it = elements_.find(id);
  if (it == elements_.end()) return;
  unindex(it->second);
  elements_.erase(it);
}

void WorldStore::bump_next_id(const std::string& id) {
  const int64_t n = id_number(id);
  if (n >= next_id_) next_id_ = n + 1;
}

TxnResult WorldStore::apply(const std::vector<Op>& ops, int64_t expected_version) {
  if (expected_version >= 0 && expected_version != version_)
    throw WmError("version conflict: the transaction expects version " + std::to_string(expected_version) +
                  ", the world is at " + std::to_string(version_));
  if (ops.empty()) throw WmError("a transaction needs at least one operation");
  undo_.clear();
  undo_next_id_ = next_id_;
  TxnResult result;
  auto insert_rel = [this](const Relation& r) {
    relations_.insert(r);
    rel_by_node_[r.subject].insert(r);
    rel_by_node_[r.object].insert(r);
  };
  auto erase_rel = [this](const Relation& r) {
    relations_.erase(r);
    rel_by_node_[r.subject].erase(r);
    rel_by_node_[r.object].erase(r);
  };
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
            put(e);
            const std::string id = e.id;
            undo_.push_back([this, id] { erase(id); });
            result.ids.push_back(id);
            result.effect.push_back(Op{Op::AddElement, std::move(e), {}});
            break;
          }
          case Op::UpdateElement: {
            auto it = elements_.find(op.element.id);
            if (it == elements_.end()) throw WmError("no element " + op.element.id + " to update");
            check_element(op.element);
            Element old = it->second;
            put(op.element);
            undo_.push_back([this, old] { put(old); });
            result.effect.push_back(Op{Op::UpdateElement, op.element, {}});
            break;
          }
          case Op::RemoveElement: {
            auto it = elements_.find(op.element.id);
            if (it == elements_.end()) throw WmError("no element " + op.element.id + " to remove");
            Element old = it->second;
            const std::set<Relation> touching = rel_by_node_[old.id];
            for (const auto& r : touching) {
              erase_rel(r);
              undo_.push_back([insert_rel, r] { insert_rel(r); });
              result.effect.push_back(Op{Op::RemoveRelation, {}, r});
            }
            erase(old.id);
            undo_.push_back([this, old] { put(old); });
            result.effect.push_back(Op{Op::RemoveElement, Element{old.id, old.type, old.label, {}}, {}});
            break;
          }
          case Op::AddRelation: {
            const Relation& r = op.relation;
            if (!elements_.count(r.subject)) throw WmError("relation " + rel_text(r) + ": no element " + r.subject);
            if (!elements_.count(r.object)) throw WmError("relation " + rel_text(r) + ": no element " + r.object);
            if (!ontology_.is_relation(r.predicate))
              throw WmError("relation " + rel_text(r) + ": unknown relation type " + r.predicate);
            if (relations_.count(r)) break;  // already there: nothing changes
            insert_rel(r);
            undo_.push_back([erase_rel, r] { erase_rel(r); });
            result.effect.push_back(Op{Op::AddRelation, {}, r});
            break;
          }
          case Op::RemoveRelation: {
            const Relation& r = op.relation;
            if (!relations_.count(r)) throw WmError("no relation " + rel_text(r) + " to remove");
            erase_rel(r);
            undo_.push_back([insert_rel, r] { insert_rel(r); });
            result.effect.push_back(Op{Op::RemoveRelation, {}, r});
            break;
          }
          default:
            throw WmError("unknown operation kind " + std::to_string(static_cast<int>(op.kind)));
        }
      } catch (const WmError& e) {
        throw WmError(where + e.what());
      }
    }
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
  return it == elements_.end() ? nullptr : &it->second;
}

std::vector<const Element*> WorldStore::query(const Query& q) const {
  std::set<std::string> candidates;
  if (!q.ids.empty()) {
    for (const auto& id : q.ids)
      if (elements_.count(id)) candidates.insert(id);
  } else if (!q.type.empty()) {
    const std::set<std::string> one{q.type};
    for (const auto& t : q.exact_type ? one : ontology_.subclasses(q.type)) {
      auto it = by_type_.find(t);
      if (it != by_type_.end()) candidates.insert(it->second.begin(), it->second.end());
    }
  } else if (!q.label.empty()) {
    auto it = by_label_.find(q.label);
    if (it != by_label_.end()) candidates = it->second;
  } else {
    for (const auto& kv : elements_) candidates.insert(kv.first);
  }
  std::vector<const Element*> out;
  for (const auto& id : candidates) {
    const Element& e = elements_.at(id);
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
      const std::string s = pat.subject.empty() ? id : pat.subject;
      const std::string o = pat.object.empty() ? id : pat.object;
      auto rels = rel_by_node_.find(id);
      bool found = false;
      if (rels != rel_by_node_.end())
        for (const auto& r : rels->second)
          if ((s == "*" || r.subject == s) && (o == "*" || r.object == o) &&
              (pat.predicate.empty() || pat.predicate == "*" || ontology_.is_subproperty(r.predicate, pat.predicate)))
            found = true;
      ok = found;
    }
    if (ok) out.push_back(&e);
  }
  return out;
}

std::vector<Relation> WorldStore::relations_touching(const std::set<std::string>& ids) const {
  std::set<Relation> out;
  for (const auto& id : ids) {
    auto it = rel_by_node_.find(id);
    if (it != rel_by_node_.end()) out.insert(it->second.begin(), it->second.end());
  }
  return {out.begin(), out.end()};
}

const std::set<Relation>& WorldStore::relations_of(const std::string& id) const {
  static const std::set<Relation> none;
  auto it = rel_by_node_.find(id);
  return it == rel_by_node_.end() ? none : it->second;
}

std::vector<Relation> WorldStore::relations(const std::string& s, const std::string& p, const std::string& o) const {
  std::vector<Relation> out;
  const std::set<Relation>& pool = !s.empty() ? relations_of(s) : !o.empty() ? relations_of(o) : relations_;
  for (const auto& r : pool)
    if ((s.empty() || r.subject == s) && (o.empty() || r.object == o) &&
        (p.empty() || ontology_.is_subproperty(r.predicate, p)))
      out.push_back(r);
  return out;
}

void WorldStore::reset(std::vector<Element> elements, std::vector<Relation> relations, int64_t version,
                       int64_t next_id) {
  elements_.clear();
  by_type_.clear();
  by_label_.clear();
  relations_.clear();
  rel_by_node_.clear();
  undo_.clear();
  for (auto& e : elements) put(std::move(e));
  for (const auto& r : relations) {
    relations_.insert(r);
    rel_by_node_[r.subject].insert(r);
    rel_by_node_[r.object].insert(r);
  }
  version_ = version;
  next_id_ = next_id;
  for (const auto& [id, e] : elements_) bump_next_id(id);
}

}  // namespace skillbus::wm
