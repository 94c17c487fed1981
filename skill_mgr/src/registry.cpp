#include "registry.hpp"

#include <set>

namespace skillbus::skills {

namespace {

using skillbus_msgs::skill_description_t;
using skillbus_msgs::skill_param_t;

const char* kind_name(int8_t k) {
  return k == skill_param_t::REQUIRED ? "required" : k == skill_param_t::OPTIONAL ? "optional" : "inferred";
}

std::string with_article(const std::string& noun) {
  return (!noun.empty() && std::string("aeiou").find(noun[0]) != std::string::npos ? "an " : "a ") + noun;
}

const skill_param_t* param_of(const skill_description_t& d, const std::string& key) {
  for (const auto& p : d.params)
    if (p.key == key) return &p;
  return nullptr;
}

// "" or the first way `d`'s parameters differ from `known`'s (keys, data types, concepts,
// kinds; descriptions and defaults may differ). A type is its description's: the manager
// checks a start's values, parses its text and fills a compound's children by one
// implementation's declarations, and Alternatives may run any other.
std::string params_differ(const skill_description_t& d, const skill_description_t& known) {
  for (const auto& p : d.params) {
    const skill_param_t* k = param_of(known, p.key);
    if (!k) return "it has parameter " + p.key + ", which " + known.label + " has not";
    if (p.data_type != k->data_type)
      return "its parameter " + p.key + " is " + with_article(p.data_type) + ", in " + known.label + " " +
             with_article(k->data_type);
    if (p.concept != k->concept)
      return "its parameter " + p.key + " is of concept " + p.concept + ", in " + known.label + " of " + k->concept;
    if (p.param_type != k->param_type)
      return "its parameter " + p.key + " is " + kind_name(p.param_type) + ", in " + known.label + " " +
             kind_name(k->param_type);
  }
  for (const auto& k : known.params)
    if (!param_of(d, k.key)) return "it lacks parameter " + k.key + " of " + known.label;
  return "";
}

}  // namespace

std::vector<std::string> Registry::add(const skillbus_msgs::skill_register_t& reg) {
  std::vector<std::string> refused;
  incarnations_[reg.process] = reg.incarnation;
  for (auto it = by_label_.begin(); it != by_label_.end();)
    it = it->second.process == reg.process ? by_label_.erase(it) : std::next(it);
  for (const auto& d : reg.skills) {
    if (d.type.empty() || d.label.empty()) {
      refused.push_back("a skill of " + reg.process + " has no type or label");
      continue;
    }
    auto it = by_label_.find(d.label);
    if (it != by_label_.end()) {
      refused.push_back("skill " + d.label + " of " + reg.process + ": the label is served by " + it->second.process);
      continue;
    }
    std::string differs;
    for (const auto& [l, impl] : by_label_) {
      if (impl.description.type != d.type) continue;
      differs = params_differ(d, impl.description);
      if (!differs.empty()) {
        refused.push_back("skill " + d.label + " of " + reg.process + ": not the parameters of its type " + d.type +
                          " as skill " + l + " of " + impl.process + " declares them: " + differs);
        break;
      }
    }
    if (!differs.empty()) continue;
    by_label_[d.label] = Implementation{d, reg.process, reg.rpc_area, reg.incarnation};
    gone_.erase(d.type);
  }
  return refused;
}

std::vector<Implementation> Registry::find(const std::string& type, const std::string& label) const {
  std::vector<Implementation> out;
  for (const auto& [l, impl] : by_label_)
    if (impl.description.type == type && (label.empty() || l == label)) out.push_back(impl);
  return out;
}

std::vector<std::string> Registry::types() const {
  std::set<std::string> t;
  for (const auto& [l, impl] : by_label_) t.insert(impl.description.type);
  return {t.begin(), t.end()};
}

int64_t Registry::incarnation_of(const std::string& process) const {
  auto it = incarnations_.find(process);
  return it == incarnations_.end() ? 0 : it->second;
}

void Registry::remove(const std::string& process, const std::string& why) {
  for (auto it = by_label_.begin(); it != by_label_.end();) {
    if (it->second.process == process) {
      gone_[it->second.description.type] = why;
      it = by_label_.erase(it);
    } else {
      ++it;
    }
  }
  incarnations_.erase(process);
}

std::string Registry::gone(const std::string& type) const {
  auto it = gone_.find(type);
  return it == gone_.end() ? "" : it->second;
}

std::vector<std::string> Registry::processes() const {
  std::vector<std::string> out;
  for (const auto& [p, inc] : incarnations_) out.push_back(p);
  return out;
}

}  // namespace skillbus::skills
