// A placeholder without a label whose type has several implementations: at start it
// takes the first (label order) that can start (its parameters check and ground and its
// pre-conditions hold, judged without touching the blackboard), and runs it.
#pragma once

#include <memory>
#include <vector>

#include "registry.hpp"
#include "task_context.hpp"
#include "tree/processor.hpp"

namespace skillbus::skills {

class Scope;

class Alternatives : public Node {
 public:
  Alternatives(TaskContext& ctx, std::vector<Implementation> impls, std::shared_ptr<Scope> scope);
  const Children& children() const override { return chosen_; }

 protected:
  bool start() override;
  State step() override { return chosen_.front()->tick(); }
  State on_preempt() override;
  void on_reset() override { chosen_.clear(); }

 private:
  TaskContext& ctx_;
  std::vector<Implementation> impls_;
  std::shared_ptr<Scope> scope_;
  Children chosen_;
};

}  // namespace skillbus::skills
