// Invert(processor): the wrapped processor's result turned around: a success fails the
// node and a failure succeeds it (running stays running). For a skill that must NOT
// achieve something: "Locate finds no object on the table". The worked example of adding
// a processor (docs/processors.md).
#pragma once

#include "../processor.hpp"

namespace skillbus::skills {

class Invert : public Processor {
 public:
  explicit Invert(std::unique_ptr<Processor> inner) : inner_(std::move(inner)) {}
  State process(const Children& children) override {
    const State s = inner_->process(children);
    say(s == State::Running ? inner_->message() : "inverted: " + inner_->message());
    if (s == State::Success) return State::Failure;
    if (s == State::Failure) return State::Success;
    return s;
  }
  void reset() override { inner_->reset(); }
  std::string name() const override { return "Invert(" + inner_->name() + ")"; }

 private:
  std::unique_ptr<Processor> inner_;
};

}  // namespace skillbus::skills
