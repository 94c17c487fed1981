// Loop(n): runs the children in sequence (a SerialStar: its memory of finished children)
// n times; without n, forever. A failure fails the loop. A new round starts on the tick
// after the previous one ended, so a round of instantly succeeding children cannot spin
// inside one tick.
#pragma once

#include "serial_star.hpp"

namespace skillbus::skills {

class Loop : public Processor {
 public:
  explicit Loop(int rounds) : rounds_(rounds) {}
  State process(const Children& children) override {
    if (rounds_ == 0) {  // nothing to run: done at once
      say("0 rounds done");
      return State::Success;
    }
    const State s = round_.process(children);
    if (s != State::Success) {
      say("round " + std::to_string(done_ + 1) + ": " + round_.message());
      return s;
    }
    ++done_;
    round_.reset();
    if (rounds_ >= 0 && done_ >= rounds_) {
      say(std::to_string(done_) + " rounds done");
      return State::Success;
    }
    say("round " + std::to_string(done_) + " done");
    return State::Running;
  }
  void reset() override {
    round_.reset();
    done_ = 0;
  }
  std::string name() const override { return rounds_ < 0 ? "Loop" : "Loop(" + std::to_string(rounds_) + ")"; }

 private:
  int rounds_;
  SerialStar round_;
  int done_ = 0;
};

}  // namespace skillbus::skills
