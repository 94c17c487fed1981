// ParallelFf: ticks every child every tick (a child that has succeeded is left alone,
// not restarted); succeeds when all have succeeded; at the first failure preempts all
// the others and fails.
#pragma once

#include "../processor.hpp"

namespace skillbus::skills {

class ParallelFf : public Processor {
 public:
  State process(const Children& children) override {
    bool running = false;
    for (size_t i = 0; i < children.size(); ++i) {
      if (children[i]->state() == State::Success) continue;
      const State s = children[i]->tick();
      if (s == State::Failure) {
        for (const auto& c : children) c->preempt();
        say(children[i]->display_name() + " failed: " + children[i]->message());
        return State::Failure;
      }
      running |= s == State::Running;
    }
    say(running ? "running" : "all succeeded");
    return running ? State::Running : State::Success;
  }
  std::string name() const override { return "ParallelFf"; }
};

}  // namespace skillbus::skills
