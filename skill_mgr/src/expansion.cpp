#include "expansion.hpp"

#include <map>
#include <stdexcept>
#include <vector>

#include "param_check.hpp"
#include "skill_nodes.hpp"
#include "skill_params.hpp"
#include "tree/compound.hpp"
#include "tree/processor_registry.hpp"

namespace skillbus::skills {

namespace {

// "" or which remap or specify key of a tree node the child skill does not have.
std::string unknown_keys(const skillbus_msgs::skill_description_t& d, const skillbus_msgs::skill_tree_node_t& n) {
  auto has = [&d](const std::string& key) {
    for (const auto& p : d.params)
      if (p.key == key) return true;
    return false;
  };
  std::string keys;
  for (const auto& p : d.params) keys += (keys.empty() ? "" : ", ") + p.key;
  for (int r = 0; r < n.num_remaps && r < static_cast<int>(n.remap_from.size()); ++r)
    if (!has(n.remap_from[r]))
      return "remap " + n.remap_from[r] + " -> " + n.remap_to[r] + ": " + d.type + " has no parameter " +
             n.remap_from[r] + " (it has: " + keys + ")";
  for (const auto& sp : n.specify)
    if (!has(sp.key)) return "specify " + sp.key + ": " + d.type + " has no parameter " + sp.key + " (it has: " + keys + ")";
  for (const auto* conds : {&n.pre, &n.hold, &n.post})
    for (const auto& c : *conds)
      for (const auto* key : {&c.subject, &c.object})
        if (!key->empty() && !has(*key))
          return "condition " + c.label + " of the node: " + d.type + " has no parameter " + *key + " (it has: " + keys +
                 ")";
  return "";
}

// The owner's parameters, inferred again when an InferInvalid processor starts a run.
ProcessorHooks hooks_for(TaskContext& ctx, const Implementation& owner, std::shared_ptr<Scope> scope) {
  ProcessorHooks h;
  h.before_run = [&ctx, owner, scope] { return infer_invalid(ctx, owner, *scope); };
  return h;
}

}  // namespace

std::string build_expansion(TaskContext& ctx, const Implementation& owner, const std::shared_ptr<Scope>& scope,
                            const skillbus_msgs::skill_tree_t& tree, Expansion& out) {
  const std::string where = "expand of " + owner.description.label + ": ";
  if (tree.nodes.empty()) return "expand of " + owner.description.label + " gave no tree";
  std::vector<CompoundNode*> groups(tree.nodes.size(), nullptr);  // anonymous groups, by node index
  std::vector<std::shared_ptr<Scope>> scopes(tree.nodes.size());
  scopes[0] = scope;
  try {
    for (size_t i = 1; i < tree.nodes.size(); ++i) {
      const auto& n = tree.nodes[i];
      if (n.parent < 0 || static_cast<size_t>(n.parent) >= i)
        return where + "node " + std::to_string(i) + " has no valid parent";
      std::map<std::string, std::string> remap;
      for (int r = 0; r < n.num_remaps && r < static_cast<int>(n.remap_to.size()); ++r)
        remap[n.remap_from[r]] = n.remap_to[r];
      std::map<std::string, Param> specify;
      for (const auto& sp : n.specify) specify[sp.key] = sp;
      if (!n.type.empty()) {  // values fixed for a skill are checked against its description
        const auto impls = ctx.registry.find(n.type, n.label);
        for (auto& [key, sp] : specify) {
          if (impls.empty() || key.empty()) break;
          const std::string bad = fit_specified(impls.front().description, sp);
          if (!bad.empty() && !unknown_keys(impls.front().description, n).empty()) break;  // named below
          if (!bad.empty()) return where + "specify " + key + ": " + bad;
        }
      }
      scopes[i] = scopes[n.parent]->child(std::move(remap), std::move(specify));
      std::unique_ptr<Node> node;
      if (n.type.empty()) {
        if (!n.pre.empty() || !n.hold.empty() || !n.post.empty())
          return where + "node " + std::to_string(i) + " is a group (" + n.processor +
                 "): only a skill node carries conditions of its own";
        auto group = std::make_unique<CompoundNode>("", "", make_processor(n.processor, hooks_for(ctx, owner, scopes[i])));
        groups[i] = group.get();
        node = std::move(group);
      } else {
        const auto impls = ctx.registry.find(n.type, n.label);
        if (impls.empty()) {
          const std::string gone = ctx.registry.gone(n.type);
          return "no skill of type " + n.type + (n.label.empty() ? "" : " with label " + n.label) + " is available (in " +
                 owner.description.label + ")" + (gone.empty() ? "" : ": " + gone);
        }
        // A remap or specify of a key the child does not have would be ignored silently
        // (SkiROS2 does): a typo in a tree is an error that names it.
        const std::string bad = unknown_keys(impls.front().description, n);
        if (!bad.empty()) return where + bad;
        node = make_placeholder_node(ctx, n.type, n.label, scopes[i], &n);
      }
      if (n.parent == 0)
        out.top.push_back(std::move(node));
      else if (groups[n.parent])
        groups[n.parent]->add(std::move(node));
      else
        return where + "node " + std::to_string(i) + " has a skill as parent";
    }
    out.processor = make_processor(tree.nodes[0].processor, hooks_for(ctx, owner, scope));
  } catch (const std::invalid_argument& e) {  // an unknown or malformed processor
    return where + e.what();
  }
  return "";
}

}  // namespace skillbus::skills
