// RetryOnFail(n): runs the children in sequence (a SerialStar: its memory of finished
// children); when one fails, starts over from the first child on the next tick, at most
// n times (so at most n+1 attempts; without n, unbounded). Succeeds when an attempt
// succeeds. Giving up names the first attempt's failure beside the last: the first is
// usually the cause (a process killed mid-task), the later ones its consequences, and a
// retry must not hide why a task failed.
#pragma once

#include <string>

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
      if (failures_ == 1) first_failure_ = why;
      attempt_.reset();
      if (retries_ >= 0 && failures_ > retries_) {
        if (failures_ == 1 || why == first_failure_)
          say("gave up after " + std::to_string(failures_) + " attempts; " + why);
        else
          say("gave up after " + std::to_string(failures_) + " attempts; the last: " + why + "; the first: " +
              first_failure_);
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
    first_failure_.clear();
  }
  std::string name() const override {
    return retries_ < 0 ? "RetryOnFail" : "RetryOnFail(" + std::to_string(retries_) + ")";
  }

 private:
  int retries_;
  SerialStar attempt_;
  int failures_ = 0;
  std::string first_failure_;
};

}  // namespace skillbus::skills
