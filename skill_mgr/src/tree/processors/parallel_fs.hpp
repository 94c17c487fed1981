// ParallelFs: ticks every child every tick; at the first child that ends (success or
// failure) preempts the others and returns that child's result.
#pragma once

#include "../processor.hpp"

namespace skillbus::skills {

class ParallelFs : public Processor {
 public:
  State process(const Children& children) override {
    for (size_t i = 0; i < children.size(); ++i) {
      const State s = children[i]->tick();
      if (finished(s)) {
        for (const auto& c : children) c->preempt();
        say(children[i]->display_name() + (s == State::Success ? " succeeded" : " failed: " + children[i]->message()));
        return s;
      }
    }
    say("running");
    return State::Running;
  }
  std::string name() const override { return "ParallelFs"; }
};

}  // namespace skillbus::skills
