// Tree nodes that are skills of skill processes (one class per file):
//  * RemotePrimitive (remote_primitive.hpp): each lifecycle step is an RPC tick to the
//    process that serves it (START, EXECUTE, PREEMPT, END);
//  * RemoteCompound (remote_compound.hpp): when it starts, asks its process to expand it
//    and builds its children (expansion.hpp);
//  * Alternatives (alternatives.hpp): a placeholder without a label whose type has
//    several implementations takes the first that can start.
#pragma once

#include <memory>

#include "registry.hpp"
#include "skillbus_msgs/skill_tree_node_t.hpp"
#include "task_context.hpp"
#include "tree/node.hpp"

namespace skillbus::skills {

class Scope;

// A tree node's own conditions after the description's (each ConditionOr of the node with
// a label of its own, so that it never joins one of the skill's).
void add_node_conditions(skillbus_msgs::skill_description_t& d, const skillbus_msgs::skill_tree_node_t& node);
// The node for an implementation (primitive or compound).
std::unique_ptr<Node> make_skill_node(TaskContext& ctx, const Implementation& impl, std::shared_ptr<Scope> scope);
// The node for a placeholder of `type` (and `label`): that implementation, or Alternatives
// among several; null when none is registered. `own` (the tree node's own conditions, if
// any) joins each implementation's pre-, hold- and post-conditions.
std::unique_ptr<Node> make_placeholder_node(TaskContext& ctx, const std::string& type, const std::string& label,
                                            std::shared_ptr<Scope> scope,
                                            const skillbus_msgs::skill_tree_node_t* own = nullptr);

}  // namespace skillbus::skills
