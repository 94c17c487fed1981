// Grounding: when a skill starts, every element parameter that is not Optional and
// still abstract (no id) is filled in from the world model with the first element (in
// id order) of its concept (or a subclass) and label that satisfies the pre-conditions
// that concern it, jointly for parameters linked by conditions (a backtracking search
// in declaration order). If nothing fits: "cannot ground parameter X". A Required
// parameter that no pre-condition mentions is grounded only if exactly one element fits
// (else the error lists the candidates); an Inferred one takes the first that fits.
// Only abstract values are grounded: a concrete id that is not in the world is an error
// of the caller (param_check.hpp), never a value to replace.
#pragma once

#include <set>
#include <string>
#include <vector>

#include "conditions.hpp"

namespace skillbus::skills {

// Fills `params` in place (except the keys in `skip`); returns "" or the error.
std::string ground(std::vector<Param>& params, const std::vector<Condition>& pre, const wm::WorldStore& world,
                   const std::set<std::string>& skip = {});
// True if some parameter (not in `skip`) needs grounding.
bool needs_grounding(const std::vector<Param>& params, const std::set<std::string>& skip = {});

}  // namespace skillbus::skills
