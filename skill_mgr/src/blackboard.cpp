#include "blackboard.hpp"

#include <cstdio>

namespace skillbus::skills {

bool Blackboard::has(const std::string& key) const {
  auto it = values_.find(key);
  return it != values_.end() && !it->second.values.empty();
}

const Param* Blackboard::get(const std::string& key) const {
  auto it = values_.find(key);
  return it == values_.end() ? nullptr : &it->second;
}

void Blackboard::set(const std::string& key, const Param& p) {
  Param copy = p;
  copy.key = key;
  values_[key] = std::move(copy);
}

void Blackboard::give(const std::string& key, const Param& p) {
  set(key, p);
  given_.insert(key);
}

std::shared_ptr<Scope> Scope::child(std::map<std::string, std::string> remap, std::map<std::string, Param> specify) const {
  auto s = std::make_shared<Scope>();
  s->parent_ = std::make_shared<Scope>(*this);
  s->remap_ = std::move(remap);
  s->specify_ = std::move(specify);
  return s;
}

std::string Scope::key(const std::string& own) const {
  auto it = remap_.find(own);
  const std::string mine = it == remap_.end() ? own : it->second;
  return parent_ ? parent_->key(mine) : mine;
}

const Param* Scope::specified(const std::string& own) const {
  // Fixed here, else fixed for this key by an ancestor: a compound whose parent specified
  // its Object hands that Object to the children that read Object (after their remaps).
  auto it = specify_.find(own);
  if (it != specify_.end()) return &it->second;
  if (!parent_) return nullptr;
  auto r = remap_.find(own);
  return parent_->specified(r == remap_.end() ? own : r->second);
}

namespace {
// A float as ostream's default writes it (6 significant digits, %g), without a stream:
// progress formats every parameter of every primitive at every tick (docs/benchmarks.md).
void append_float(std::string& out, double f) {
  char buf[32];
  const int n = std::snprintf(buf, sizeof(buf), "%g", f);
  out.append(buf, n > 0 ? static_cast<size_t>(n) : 0);
}

void append_value(std::string& out, const skillbus_msgs::skill_value_t& v) {
  using skillbus_msgs::skill_value_t;
  switch (v.type) {
    case skill_value_t::STRING: out += v.s; break;
    case skill_value_t::INT: out += std::to_string(v.i); break;
    case skill_value_t::FLOAT: append_float(out, v.f); break;
    case skill_value_t::BOOL: out += v.b ? "true" : "false"; break;
    case skill_value_t::ELEMENT: out += v.element.id.empty() ? v.element.type : v.element.id; break;
    case skill_value_t::JSON: out += v.s; break;
    default: out += "?";
  }
}
}  // namespace

std::string value_text(const skillbus_msgs::skill_value_t& v) {
  std::string out;
  append_value(out, v);
  return out;
}

std::string params_text(const std::vector<Param>& params) {
  std::string out;
  for (const auto& p : params) {
    out += p.key + "=";
    for (size_t i = 0; i < p.values.size(); ++i) {
      if (i) out += ",";
      append_value(out, p.values[i]);
    }
    out += "\n";
  }
  return out;
}

}  // namespace skillbus::skills
