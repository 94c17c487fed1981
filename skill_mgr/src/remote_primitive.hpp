// A primitive of a skill process: each lifecycle step is an RPC tick to the process
// (START, EXECUTE, PREEMPT, END) with the node's parameters from the blackboard; what the
// skill changed goes back to the blackboard. Hold-conditions are checked before every
// tick after the first (the first was checked at start), post-conditions on success.
#pragma once

#include <memory>
#include <vector>

#include "blackboard.hpp"
#include "registry.hpp"
#include "task_context.hpp"
#include "tree/node.hpp"

namespace skillbus::skills {

class RemotePrimitive : public Node {
 public:
  RemotePrimitive(TaskContext& ctx, Implementation impl, std::shared_ptr<Scope> scope);
  const std::vector<Param>& last_params() const { return params_; }
  // params_text(last_params()), formatted once per change: the task's progress shows it for
  // every primitive of the tree at every tick.
  const std::string& last_params_text() const;

 protected:
  bool start() override;
  State step() override;
  State on_preempt() override;
  void finish() override;

 private:
  State call(int8_t action);
  void set_params(std::vector<Param> params);
  TaskContext& ctx_;
  Implementation impl_;
  std::shared_ptr<Scope> scope_;
  std::vector<Param> params_;  // (assigned through set_params: the text below follows it)
  mutable std::string params_text_;
  mutable bool params_text_stale_ = true;
  int64_t instance_ = 0;
  int64_t incarnation_ = 0;  // of the skill process that runs this instance
  bool first_ = true;
  bool unresponsive_ = false;  // its process did not answer: do not wait for it again
  bool ended_ = false;  // its last reply said the tick ended the instance: no END to send
  int64_t wm_version_ = -1;    // the world version the skill has seen (from its last reply)
  // Until this sim time the skill's execute() would change nothing (its last reply's
  // idle_until_ns): execute ticks are skipped while its parameters stay the same.
  int64_t idle_until_ns_ = 0;
};

}  // namespace skillbus::skills
