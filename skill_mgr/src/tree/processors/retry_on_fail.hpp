// RetryOnFail(n): runs the children in sequence (a SerialStar: its memory of finished
// children); when one fails, starts over from the first child on the next tick, at most
// n times (so at most n+1 attempts; without n, unbounded). Succeeds when an attempt
// succeeds.
#pragma once

#include "serial_star.hpp"

namespace skillbus::skills {

class RetryOnFail : public Processor {
 public:
  explicit RetryOnFail(int retries) : retries_(retries) {}
  State process(const Children& children) override {
    const State s = attempt_.process(children);
    if (s == State::Running) {
      say("attempt " + std::to_string(failures_ + 1) + ": " + attempt_.message());
      return State::Running;
    }
    if (s == State::Failure) {
      const std::string why = attempt_.message();
      ++failures_;
      attempt_.reset();
      if (retries_ >= 0 && failures_ > retries_) {
        say("gave up after " + std::to_string(failures_) + " attempts; " + why);
        return State::Failure;
      }
      say("attempt " + std::to_string(failures_) + " failed (" + why + "); retrying");
      return State::Running;
    }
    say("succeeded at attempt " + std::to_string(failures_ + 1));
    return State::Success;
  }
  void reset() override {
    attempt_.reset();
    failures_ = 0;
  }
  std::string name() const override {
    return retries_ < 0 ? "RetryOnFail" : "RetryOnFail(" + std::to_string(retries_) + ")";
  }

 private:
  int retries_;
  SerialStar attempt_;
  int failures_ = 0;
};

}  // namespace skillbus::skills
