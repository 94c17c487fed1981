// NoFail(processor): the wrapped processor's result, except that a failure becomes a
// success (the message keeps the reason).
#pragma once

#include "../processor.hpp"

namespace skillbus::skills {

class NoFail : public Processor {
 public:
  explicit NoFail(std::unique_ptr<Processor> inner) : inner_(std::move(inner)) {}
  State process(const Children& children) override {
    const State s = inner_->process(children);
    if (s == State::Failure) {
      say("failure ignored: " + inner_->message());
      return State::Success;
    }
    say(inner_->message());
    return s;
  }
  void reset() override { inner_->reset(); }
  std::string name() const override { return "NoFail(" + inner_->name() + ")"; }

 private:
  std::unique_ptr<Processor> inner_;
};

}  // namespace skillbus::skills
