// Selector: ticks the children in order until one succeeds. Returns at the first child
// that runs or succeeds, preempting the later children that still run; fails when all
// fail. Failed children are tried again (restarted) on the next tick.
#pragma once

#include "../processor.hpp"

namespace skillbus::skills {

class Selector : public Processor {
 public:
  State process(const Children& children) override {
    for (size_t i = 0; i < children.size(); ++i) {
      const State s = children[i]->tick();
      if (s != State::Failure) {
        preempt_from(children, i + 1);
        say(children[i]->display_name() + (s == State::Running ? " running" : " succeeded"));
        return s;
      }
    }
    // Named by the last child's failure: the fallback, usually the one that says why (a
    // failed guard before it is the expected case, not the cause).
    say(children.empty() ? std::string("all children failed")
                         : "all children failed; the last: " + children.back()->display_name() + " failed: " +
                               children.back()->message());
    return State::Failure;
  }
  std::string name() const override { return "Selector"; }
};

}  // namespace skillbus::skills
