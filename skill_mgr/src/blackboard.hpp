// Parameters between skills. One blackboard per task, keyed by parameter name after
// remaps: a node reads its parameters from it when it starts and on every tick, and
// writes them back after each tick, so outputs of one skill are inputs of the next.
//
// A node sees the blackboard through a Scope: its own key -> the blackboard key (its
// remaps, composed with its parent's), and values its parent fixed (specify).
#pragma once

#include <map>
#include <memory>
#include <set>
#include <string>
#include <vector>

#include "skillbus_msgs/skill_param_t.hpp"

namespace skillbus::skills {

using Param = skillbus_msgs::skill_param_t;

class Blackboard {
 public:
  bool has(const std::string& key) const;  // holds at least one value
  const Param* get(const std::string& key) const;
  void set(const std::string& key, const Param& p);
  // A value the user gave when starting the task: it overrides a static value (a Required
  // parameter with a value in its description) wherever that key is read.
  void give(const std::string& key, const Param& p);
  bool given(const std::string& key) const { return given_.count(key) > 0; }
  const std::map<std::string, Param>& all() const { return values_; }

 private:
  std::map<std::string, Param> values_;
  std::set<std::string> given_;
};

class Scope {
 public:
  Scope() = default;  // the task's root: keys are blackboard keys
  // A child's scope: its remaps (child key -> key in this scope) and specified values.
  std::shared_ptr<Scope> child(std::map<std::string, std::string> remap, std::map<std::string, Param> specify) const;
  std::string key(const std::string& own) const;       // the blackboard key
  const Param* specified(const std::string& own) const;  // fixed by a parent or an ancestor, or null

 private:
  std::shared_ptr<const Scope> parent_;
  std::map<std::string, std::string> remap_;
  std::map<std::string, Param> specify_;
};

std::string value_text(const skillbus_msgs::skill_value_t& v);
std::string params_text(const std::vector<Param>& params);  // "key=value" lines

}  // namespace skillbus::skills
