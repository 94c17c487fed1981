#include "skill_nodes.hpp"

#include "alternatives.hpp"
#include "remote_compound.hpp"
#include "remote_primitive.hpp"

namespace skillbus::skills {

std::unique_ptr<Node> make_skill_node(TaskContext& ctx, const Implementation& impl, std::shared_ptr<Scope> scope) {
  if (impl.description.compound) return std::make_unique<RemoteCompound>(ctx, impl, std::move(scope));
  return std::make_unique<RemotePrimitive>(ctx, impl, std::move(scope));
}

std::unique_ptr<Node> make_placeholder_node(TaskContext& ctx, const std::string& type, const std::string& label,
                                            std::shared_ptr<Scope> scope) {
  auto impls = ctx.registry.find(type, label);
  if (impls.empty()) return nullptr;
  if (impls.size() > 1 && label.empty())  // by type only: the first implementation that can start
    return std::make_unique<Alternatives>(ctx, std::move(impls), std::move(scope));
  return make_skill_node(ctx, impls.front(), std::move(scope));
}

}  // namespace skillbus::skills
