// Parameter checks at the boundary: what a user (or a compound's specify) hands a skill is
// checked before the skill is ticked, so that a wrong value fails the start with a named
// error instead of becoming another value.
//
//   check_given     at `start`: every key is a parameter of the skill, every value has
//                   the parameter's data type (no world model needed)
//   parse_text      `--start KEY=VALUE`: the text parsed strictly by the declared type
//   check_elements  at a skill's start: every concrete element id exists in the world
//                   model and is of the parameter's concept (or below it); the value is
//                   replaced by the world's copy (all its properties)
#pragma once

#include <string>
#include <vector>

#include "blackboard.hpp"
#include "skillbus/wm/store.hpp"
#include "skillbus_msgs/skill_description_t.hpp"

namespace skillbus::skills {

// "" or why the given parameters do not fit the description.
std::string check_given(const skillbus_msgs::skill_description_t& d, const std::vector<Param>& given);

// What a skill process answers a tick with: "" or the first parameter that the skill does
// not have, or whose values are not of its declared type (whatever the parameter's own
// data_type says). Such a value would reach the blackboard, and the skill's siblings.
std::string check_returned(const skillbus_msgs::skill_description_t& d, const std::vector<Param>& returned);

// Fills `p` (key and one text value) with the typed value of its declaration; "" or why not.
// Bools: true/false/1/0 (any case); lists and dicts: JSON text, kept as JSON.
std::string parse_text(const skillbus_msgs::skill_description_t& d, Param& p);

// A value a compound's tree fixes for a child (specify): checked like a given value; a
// list parameter specified as several values (a Python list) becomes one JSON list.
// "" or why it does not fit.
std::string fit_specified(const skillbus_msgs::skill_description_t& d, Param& p);

// Element parameters with a concrete id: "" or the first that is missing or of the wrong
// concept. `skip` names keys not to check (the manager's own Robot without a world model).
std::string check_elements(std::vector<Param>& params, const wm::WorldStore& world,
                           const std::vector<std::string>& skip = {});

// True if the value names a concrete element (an id).
bool concrete_element(const skillbus_msgs::skill_value_t& v);

}  // namespace skillbus::skills
