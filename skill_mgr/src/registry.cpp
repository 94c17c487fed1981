#include "registry.hpp"

#include <set>

namespace skillbus::skills {

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
