// SerialStar (and its deprecated alias Sequential, the default processor): like Serial,
// but remembers which children succeeded and does not tick them again. The memory is
// cleared when the node ends (success, failure, preemption) or is reset.
#pragma once

#include "../processor.hpp"

namespace skillbus::skills {

class SerialStar : public Processor {
 public:
  State process(const Children& children) override {
    for (; next_ < children.size(); ++next_) {
      const State s = children[next_]->tick();
      if (s != State::Success) {
        say(children[next_]->display_name() + (s == State::Running ? " running" : " failed: " + children[next_]->message()));
        return s;
      }
    }
    say("all succeeded");
    return State::Success;
  }
  void reset() override { next_ = 0; }
  std::string name() const override { return "SerialStar"; }

 private:
  size_t next_ = 0;
};

}  // namespace skillbus::skills
