#include "skill_nodes.hpp"

#include "alternatives.hpp"
#include "remote_compound.hpp"
#include "remote_primitive.hpp"

namespace skillbus::skills {

std::unique_ptr<Node> make_skill_node(TaskContext& ctx, const Implementation& impl, std::shared_ptr<Scope> scope) {
  if (impl.description.compound) return std::make_unique<RemoteCompound>(ctx, impl, std::move(scope));
  return std::make_unique<RemotePrimitive>(ctx, impl, std::move(scope));
}

namespace {

// The node's conditions after the skill's. A ConditionOr is the run of members that share
// an or_label: a node's that happens to share the label of the skill's last one would join
// it ((A or B) and (C or D) read as A or B or C or D), so the node's get labels of their own.
void append(std::vector<skillbus_msgs::skill_condition_t>& to, int32_t& count,
            const std::vector<skillbus_msgs::skill_condition_t>& more) {
  for (auto c : more) {
    if (!c.or_label.empty()) c.or_label = "node: " + c.or_label;
    to.push_back(std::move(c));
  }
  count = static_cast<int32_t>(to.size());
}

}  // namespace

void add_node_conditions(skillbus_msgs::skill_description_t& d, const skillbus_msgs::skill_tree_node_t& node) {
  append(d.pre, d.num_pre, node.pre);
  append(d.hold, d.num_hold, node.hold);
  append(d.post, d.num_post, node.post);
}

std::unique_ptr<Node> make_placeholder_node(TaskContext& ctx, const std::string& type, const std::string& label,
                                            std::shared_ptr<Scope> scope, const skillbus_msgs::skill_tree_node_t* own) {
  auto impls = ctx.registry.find(type, label);
  if (impls.empty()) return nullptr;
  if (own)  // (the copies the registry gave: the registered descriptions stay as they are)
    for (auto& impl : impls) add_node_conditions(impl.description, *own);
  if (impls.size() > 1 && label.empty())  // by type only: the first implementation that can start
    return std::make_unique<Alternatives>(ctx, std::move(impls), std::move(scope));
  return make_skill_node(ctx, impls.front(), std::move(scope));
}

}  // namespace skillbus::skills
