// SelectorStar: like Selector, with memory of the children already tried: a child that
// failed is not ticked again until the node ends or is reset.
#pragma once

#include "../processor.hpp"

namespace skillbus::skills {

class SelectorStar : public Processor {
 public:
  State process(const Children& children) override {
    for (; next_ < children.size(); ++next_) {
      const State s = children[next_]->tick();
      if (s != State::Failure) {
        say(children[next_]->display_name() + (s == State::Running ? " running" : " succeeded"));
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
  void reset() override { next_ = 0; }
  std::string name() const override { return "SelectorStar"; }

 private:
  size_t next_ = 0;
};

}  // namespace skillbus::skills
