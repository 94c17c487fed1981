// Grounding: when a skill starts, every element parameter that is not Optional and
// still abstract (no id) is filled in from the world model with the first element (in
// id order) of its concept (or a subclass) and label that satisfies the pre-conditions
// that concern it, jointly for parameters linked by conditions (a backtracking search
// in declaration order). If nothing fits: "cannot ground parameter X".
#pragma once

#include <string>
#include <vector>

#include "conditions.hpp"

namespace skillbus::skills {

// Fills `params` in place; returns "" or the error.
std::string ground(std::vector<Param>& params, const std::vector<Condition>& pre, const wm::WorldStore& world);
// True if some parameter needs grounding.
bool needs_grounding(const std::vector<Param>& params);

}  // namespace skillbus::skills
