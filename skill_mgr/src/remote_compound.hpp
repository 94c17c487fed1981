// A compound skill of a skill process: when it starts (parameters checked and grounded,
// pre- and hold-conditions hold) it asks its process to expand it (RPC expand) and builds
// its children (expansion.hpp). Hold-conditions are checked on every tick, post-conditions
// when it succeeds.
#pragma once

#include <memory>

#include "blackboard.hpp"
#include "registry.hpp"
#include "task_context.hpp"
#include "tree/compound.hpp"

namespace skillbus::skills {

class RemoteCompound : public CompoundNode {
 public:
  RemoteCompound(TaskContext& ctx, Implementation impl, std::shared_ptr<Scope> scope);

 protected:
  bool start() override;
  State step() override;

 private:
  TaskContext& ctx_;
  Implementation impl_;
  std::shared_ptr<Scope> scope_;
};

}  // namespace skillbus::skills
