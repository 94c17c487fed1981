// Checking a skill's conditions (skill model: pre at start, hold every tick, post at the
// end) against the manager's world replica, with the node's parameters.
//
//   IsSpecified / Generate   the parameter has a value (an element: a concrete one)
//   HasProperty              the element has the property
//   Property                 the element's property compares with the value (=, !=, <, ...)
//   Relation                 the relation holds between the two elements (subproperties count)
//   AbstractRelation         the ontology allows it between their concepts
//   OnType                   the element's concept is the type or below it
// Members of one ConditionOr (same or_label) hold when any does.
#pragma once

#include <string>
#include <vector>

#include "blackboard.hpp"
#include "skillbus/wm/store.hpp"
#include "skillbus_msgs/skill_condition_t.hpp"

namespace skillbus::skills {

using Condition = skillbus_msgs::skill_condition_t;

struct ConditionResult {
  bool ok = true;
  std::string failed;  // label of the first condition that does not hold, and why
};

// `world` may be null (no world model): conditions that need it then fail, saying so.
ConditionResult check_conditions(const std::vector<Condition>& conditions, const std::vector<Param>& params,
                                 const wm::WorldStore* world);
bool conditions_need_world(const std::vector<Condition>& conditions);

}  // namespace skillbus::skills
