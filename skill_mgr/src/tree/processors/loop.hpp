// Loop(n): runs the children in sequence (with SerialStar's memory) n times; without n,
// forever. A failure fails the loop. A new round starts on the tick after the previous
// one ended, so a round of instantly succeeding children cannot spin inside one tick.
#pragma once

#include "../processor.hpp"

namespace skillbus::skills {

class Loop : public Processor {
 public:
  explicit Loop(int rounds) : rounds_(rounds) {}
  State process(const Children& children) override {
    for (; next_ < children.size(); ++next_) {
      const State s = children[next_]->tick();
      if (s == State::Failure) {
        say("round " + std::to_string(done_ + 1) + ": " + children[next_]->type() + " failed: " + children[next_]->message());
        return State::Failure;
      }
      if (s == State::Running) {
        say("round " + std::to_string(done_ + 1) + ": " + children[next_]->type() + " running");
        return State::Running;
      }
    }
    ++done_;
    next_ = 0;
    if (rounds_ >= 0 && done_ >= rounds_) {
      say(std::to_string(done_) + " rounds done");
      return State::Success;
    }
    say("round " + std::to_string(done_) + " done");
    return State::Running;
  }
  void reset() override { next_ = 0; done_ = 0; }
  std::string name() const override { return rounds_ < 0 ? "Loop" : "Loop(" + std::to_string(rounds_) + ")"; }

 private:
  int rounds_;
  size_t next_ = 0;
  int done_ = 0;
};

}  // namespace skillbus::skills
