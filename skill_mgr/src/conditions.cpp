#include "conditions.hpp"

#include <cmath>

namespace skillbus::skills {

using skillbus_msgs::skill_value_t;

namespace {

const Param* find(const std::vector<Param>& params, const std::string& key) {
  for (const auto& p : params)
    if (p.key == key) return &p;
  return nullptr;
}

// The element id in a parameter, or "" when it holds no concrete element.
std::string element_id(const Param* p) {
  if (!p || p->values.empty() || p->values[0].type != skill_value_t::ELEMENT) return "";
  return p->values[0].element.id;
}

std::string element_type(const Param* p, const wm::WorldStore* world) {
  if (!p || p->values.empty() || p->values[0].type != skill_value_t::ELEMENT) return "";
  if (world && !p->values[0].element.id.empty())
    if (const wm::Element* e = world->get(p->values[0].element.id)) return e->type;
  return p->values[0].element.type.empty() ? p->concept : p->values[0].element.type;
}

bool compare(const wm::Value& have, const std::string& op, const skill_value_t& want) {
  auto number = [](const wm::Value& v, double& out) {
    if (auto d = std::get_if<double>(&v)) return out = *d, true;
    if (auto i = std::get_if<int64_t>(&v)) return out = static_cast<double>(*i), true;
    return false;
  };
  double a = 0, b = 0;
  const bool want_number = want.type == skill_value_t::FLOAT || want.type == skill_value_t::INT;
  b = want.type == skill_value_t::FLOAT ? want.f : static_cast<double>(want.i);
  if (want_number && number(have, a)) {
    if (op == "=") return a == b;
    if (op == "!=") return a != b;
    if (op == ">") return a > b;
    if (op == ">=") return a >= b;
    if (op == "<") return a < b;
    if (op == "<=") return a <= b;
    return false;
  }
  bool equal = false;
  if (auto s = std::get_if<std::string>(&have)) equal = want.type == skill_value_t::STRING && *s == want.s;
  if (auto x = std::get_if<bool>(&have)) equal = want.type == skill_value_t::BOOL && *x == static_cast<bool>(want.b);
  if (op == "=") return equal;
  if (op == "!=") return !equal;
  return false;
}

// Whether the condition holds (before desired_state); `why` is set when it cannot be
// judged (and then the result means nothing).
bool holds(const Condition& c, const std::vector<Param>& params, const wm::WorldStore* world, std::string& why) {
  const Param* subj = find(params, c.subject);
  if (c.kind == "IsSpecified" || c.kind == "Generate") {
    if (!subj) return why = "no parameter " + c.subject, false;
    if (subj->values.empty()) return false;
    return subj->values[0].type != skill_value_t::ELEMENT || !subj->values[0].element.id.empty();
  }
  if (!world) return why = "no world model to check it against", false;
  if (c.kind == "AbstractRelation") {
    const std::string s = element_type(subj, world), o = element_type(find(params, c.object), world);
    if (s.empty() || o.empty()) return why = "no concept for " + c.subject + " or " + c.object, false;
    return world->ontology().may_relate(s, c.owl, o);
  }
  const std::string sid = element_id(subj);
  const wm::Element* e = sid.empty() ? nullptr : world->get(sid);
  if (!e) return why = c.subject + " is not an element of the world model", false;
  if (c.kind == "HasProperty") return e->properties.count(c.owl) > 0;
  if (c.kind == "Property") {
    auto it = e->properties.find(c.owl);
    if (it == e->properties.end() || it->second.empty()) return false;
    return compare(it->second.front(), c.op, c.value);
  }
  if (c.kind == "OnType") return world->ontology().is_subclass(e->type, c.owl);
  if (c.kind == "Relation") {
    const std::string oid = element_id(find(params, c.object));
    if (oid.empty() || !world->get(oid)) return why = c.object + " is not an element of the world model", false;
    return !world->relations(sid, c.owl, oid).empty();
  }
  return why = "unknown condition kind " + c.kind, false;
}

}  // namespace

bool conditions_need_world(const std::vector<Condition>& conditions) {
  for (const auto& c : conditions)
    if (c.kind != "IsSpecified" && c.kind != "Generate") return true;
  return false;
}

ConditionResult check_conditions(const std::vector<Condition>& conditions, const std::vector<Param>& params,
                                 const wm::WorldStore* world) {
  // A condition about an optional parameter that has no value is not judged (it holds):
  // the skill runs without it (IsSpecified is the way to ask for one).
  auto unset_optional = [&](const Condition& c) {
    if (c.kind == "IsSpecified" || c.kind == "Generate") return false;
    for (const auto* k : {&c.subject, &c.object}) {
      const Param* p = k->empty() ? nullptr : find(params, *k);
      if (p && p->param_type == skillbus_msgs::skill_param_t::OPTIONAL &&
          (p->values.empty() || (p->values[0].type == skill_value_t::ELEMENT && p->values[0].element.id.empty())))
        return true;
    }
    return false;
  };
  for (size_t i = 0; i < conditions.size();) {
    if (conditions[i].or_label.empty() && unset_optional(conditions[i])) {
      ++i;
      continue;
    }
    // A ConditionOr: the run of conditions with the same non-empty or_label.
    size_t j = i + 1;
    while (!conditions[i].or_label.empty() && j < conditions.size() && conditions[j].or_label == conditions[i].or_label)
      ++j;
    bool any = false;
    std::string why_all;
    for (size_t k = i; k < j; ++k) {
      std::string why;
      const bool held = holds(conditions[k], params, world, why);
      // What cannot be judged (no world model, an element that is not there) fails the
      // condition whatever its desired state: "not holding X" is no answer about a
      // missing X.
      const bool ok = why.empty() && held == static_cast<bool>(conditions[k].desired_state);
      any |= ok;
      if (!ok) why_all += (why_all.empty() ? "" : "; ") + conditions[k].label + (why.empty() ? "" : " (" + why + ")");
    }
    if (!any)
      return {false, conditions[i].or_label.empty() ? why_all : conditions[i].or_label + ": " + why_all};
    i = j;
  }
  return {};
}

}  // namespace skillbus::skills
