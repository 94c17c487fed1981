// A compound skill's children, built from its expansion (skill_tree_t, in preorder):
// placeholders become skill nodes (skill_nodes.hpp), anonymous groups compound nodes under
// their processor; remaps and specified values become the children's scopes. A tree that
// names an unknown skill or processor, a remap or specify of a key the child does not have,
// or a malformed parent link is refused with the reason.
#pragma once

#include <memory>
#include <string>

#include "blackboard.hpp"
#include "registry.hpp"
#include "skillbus_msgs/skill_tree_t.hpp"
#include "task_context.hpp"
#include "tree/processor.hpp"

namespace skillbus::skills {

struct Expansion {
  Children top;                          // the compound's children
  std::unique_ptr<Processor> processor;  // the compound's own processor
};

// "" or why `tree` cannot be the children of `owner` (running in `scope`).
std::string build_expansion(TaskContext& ctx, const Implementation& owner, const std::shared_ptr<Scope>& scope,
                            const skillbus_msgs::skill_tree_t& tree, Expansion& out);

}  // namespace skillbus::skills
