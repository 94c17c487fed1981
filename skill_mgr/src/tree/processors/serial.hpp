// Serial: ticks the children in order until all succeed. Children that finished in an
// earlier tick are ticked again (and so restarted). Returns at the first child that has
// not succeeded (running or failed), preempting the later children that still run.
#pragma once

#include "../processor.hpp"

namespace skillbus::skills {

class Serial : public Processor {
 public:
  State process(const Children& children) override {
    for (size_t i = 0; i < children.size(); ++i) {
      const State s = children[i]->tick();
      if (s != State::Success) {
        preempt_from(children, i + 1);
        say(children[i]->display_name() + (s == State::Running ? " running" : " failed: " + children[i]->message()));
        return s;
      }
    }
    say("all succeeded");
    return State::Success;
  }
  std::string name() const override { return "Serial"; }
};

}  // namespace skillbus::skills
