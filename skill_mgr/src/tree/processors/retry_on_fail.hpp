// RetryOnFail(n): runs the children in sequence (with SerialStar's memory); when one
// fails, starts over from the first child on the next tick, at most n times (so at most
// n+1 attempts; without n, unbounded). Succeeds when an attempt succeeds.
#pragma once

#include "../processor.hpp"

namespace skillbus::skills {

class RetryOnFail : public Processor {
 public:
  explicit RetryOnFail(int retries) : retries_(retries) {}
  State process(const Children& children) override {
    for (; next_ < children.size(); ++next_) {
      const State s = children[next_]->tick();
      if (s == State::Running) {
        say("attempt " + std::to_string(failures_ + 1) + ": " + children[next_]->type() + " running");
        return State::Running;
      }
      if (s == State::Failure) {
        const std::string why = children[next_]->type() + " failed: " + children[next_]->message();
        ++failures_;
        next_ = 0;
        if (retries_ >= 0 && failures_ > retries_) {
          say("gave up after " + std::to_string(failures_) + " attempts; " + why);
          return State::Failure;
        }
        say("attempt " + std::to_string(failures_) + " failed (" + why + "); retrying");
        return State::Running;
      }
    }
    say("succeeded at attempt " + std::to_string(failures_ + 1));
    return State::Success;
  }
  void reset() override { next_ = 0; failures_ = 0; }
  std::string name() const override {
    return retries_ < 0 ? "RetryOnFail" : "RetryOnFail(" + std::to_string(retries_) + ")";
  }

 private:
  int retries_;
  size_t next_ = 0;
  int failures_ = 0;
};

}  // namespace skillbus::skills
