// A skill node's parameters: gathered from the blackboard through the node's scope,
// checked and grounded when it starts, re-inferred by InferInvalid, and the conditions
// judged on them. (Checks of single values: param_check.hpp; grounding: grounding.hpp.)
#pragma once

#include <string>
#include <vector>

#include "blackboard.hpp"
#include "registry.hpp"
#include "skillbus/wm/store.hpp"
#include "task_context.hpp"

namespace skillbus::skills {

// A node's parameters, gathered for a tick: specified by a parent, else static (a
// required parameter with a value in the description, unless the user gave that key),
// else from the blackboard, else an optional parameter's default. `missing` names
// required parameters without a value. With `world`, element values are re-read from it
// (a deleted element is dropped).
std::vector<Param> gather_params(const skillbus_msgs::skill_description_t& d, const Scope& scope,
                                 Blackboard& bb, std::string* missing, const wm::WorldStore* world = nullptr);
// What gather_params writes to the blackboard (its static parameters), without gathering:
// for a tick that needs no parameter values (a compound without hold- or post-conditions).
void write_static_params(const skillbus_msgs::skill_description_t& d, const Scope& scope, Blackboard& bb);
// The id of the one robot (a sumo:Agent: skiros:Robot, cora:Robot) labelled `label` in `world` into `id`;
// "" or why not (none, several).
std::string find_robot(const wm::WorldStore& world, const std::string& label, std::string* id);
// At a skill's start: gather, check concrete elements against the world, ground abstract
// ones, check pre- and hold-conditions. Returns "" or why the skill cannot start. With
// `dry_run` the blackboard is not written (choosing among implementations).
std::string prepare_start(TaskContext& ctx, const Implementation& impl, const Scope& scope, std::vector<Param>& params,
                          bool dry_run = false);
// InferInvalid: element parameters of `impl` whose element is gone from the world model
// (or never was concrete, or a failing pre-condition is about it) are grounded again and
// written to the blackboard. "" or why not.
std::string infer_invalid(TaskContext& ctx, const Implementation& impl, const Scope& scope);
// "" or which condition does not hold.
std::string check_hold(TaskContext& ctx, const Implementation& impl, const std::vector<Param>& params);
std::string check_post(TaskContext& ctx, const Implementation& impl, const std::vector<Param>& params);
// True if both hold the same values (compared by their encoding).
bool same_values(const Param& a, const Param& b);

}  // namespace skillbus::skills
