#include "grounding.hpp"

#include <functional>
#include <set>

#include "skillbus/wm/convert.hpp"

namespace skillbus::skills {

using skillbus_msgs::skill_param_t;
using skillbus_msgs::skill_value_t;

namespace {

bool abstract_element(const Param& p) {
  return p.data_type == "element" && p.param_type != skill_param_t::OPTIONAL &&
         (p.values.empty() || (p.values[0].type == skill_value_t::ELEMENT && p.values[0].element.id.empty()));
}

std::set<std::string> keys_of(const Condition& c) {
  std::set<std::string> k;
  if (!c.subject.empty()) k.insert(c.subject);
  if (!c.object.empty()) k.insert(c.object);
  return k;
}

}  // namespace

bool needs_grounding(const std::vector<Param>& params, const std::set<std::string>& skip) {
  for (const auto& p : params)
    if (abstract_element(p) && !skip.count(p.key)) return true;
  return false;
}

std::string ground(std::vector<Param>& params, const std::vector<Condition>& pre, const wm::WorldStore& world,
                   const std::set<std::string>& skip) {
  std::vector<size_t> todo;
  for (size_t i = 0; i < params.size(); ++i)
    if (abstract_element(params[i]) && !skip.count(params[i].key)) todo.push_back(i);
  if (todo.empty()) return "";
  // A Required parameter that no pre-condition constrains is grounded only when the
  // world has exactly one candidate (the robot's one arm); among several, the first
  // would be an arbitrary pick: a wrong target, not a choice. Inferred parameters are
  // the skill's explicit wish to be filled in, so they take the first that fits.
  for (size_t i : todo) {
    const Param& p = params[i];
    if (p.param_type == skill_param_t::INFERRED) continue;
    bool constrained = false;
    for (const auto& c : pre) constrained |= keys_of(c).count(p.key) > 0;
    if (constrained) continue;
    const skill_value_t wanted = p.values.empty() ? skill_value_t{} : p.values[0];
    wm::Query q;
    q.type = !wanted.element.type.empty() ? wanted.element.type : p.concept;
    q.label = wanted.element.label;
    const auto found = world.query(q);
    if (found.size() <= 1) continue;
    std::string some;
    for (size_t k = 0; k < found.size() && k < 4; ++k) some += (k ? ", " : "") + found[k]->id;
    return "cannot ground parameter " + p.key + ": " + std::to_string(found.size()) + " elements are a " + q.type +
           (q.label.empty() ? "" : " labelled " + q.label) + " (" + some + (found.size() > 4 ? ", ..." : "") +
           ") and no pre-condition says which; give one (" + p.key + "=ID)";
  }
  // Assigned: parameters with a concrete value (an unset optional one is not: conditions
  // about it cannot be judged while grounding).
  std::set<std::string> assigned;
  for (size_t i = 0; i < params.size(); ++i) {
    const Param& p = params[i];
    const bool concrete = !p.values.empty() && (p.data_type != "element" || !p.values[0].element.id.empty());
    if ((concrete && !abstract_element(p)) || skip.count(p.key)) assigned.insert(p.key);
  }

  // Pre-conditions whose parameters are all assigned once `key` is (checked right then).
  auto ready_conditions = [&](const std::string& key) {
    std::vector<Condition> out;
    for (const auto& c : pre) {
      if (!c.or_label.empty()) continue;  // an Or is checked whole, after grounding
      const auto ks = keys_of(c);
      if (!ks.count(key)) continue;
      bool all = true;
      for (const auto& k : ks) all &= assigned.count(k) > 0 || k == key;
      if (all) out.push_back(c);
    }
    return out;
  };

  std::string failed_key;
  std::function<bool(size_t)> search = [&](size_t n) -> bool {
    if (n == todo.size()) return true;
    Param& p = params[todo[n]];
    const skill_value_t wanted = p.values.empty() ? skill_value_t{} : p.values[0];
    const std::string concept_name = !wanted.element.type.empty() ? wanted.element.type : p.concept;
    const std::string label = wanted.element.label;
    wm::Query q;
    q.type = concept_name;
    q.label = label;
    const auto checks = ready_conditions(p.key);
    for (const wm::Element* e : world.query(q)) {
      skill_value_t v{};
      v.type = skill_value_t::ELEMENT;
      v.element = wm::to_msg(*e);
      p.values = {v};
      p.num_values = 1;
      assigned.insert(p.key);
      if (check_conditions(checks, params, &world).ok && search(n + 1)) return true;
      assigned.erase(p.key);
    }
    p.values = {wanted};
    p.num_values = 1;
    if (failed_key.empty()) failed_key = p.key;
    return false;
  };
  if (search(0)) return "";
  const Param* p = nullptr;
  for (const auto& x : params)
    if (x.key == failed_key) p = &x;
  return "cannot ground parameter " + failed_key +
         (p && !p->values.empty() ? " (" + (p->values[0].element.type.empty() ? p->concept : p->values[0].element.type) +
                                        (p->values[0].element.label.empty() ? "" : " labelled " + p->values[0].element.label) + ")"
                                  : "");
}

}  // namespace skillbus::skills
