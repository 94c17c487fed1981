// InferInvalid: when a run starts (the first tick after the node started or was reset,
// e.g. every round of an enclosing Loop), asks its owner to ground the compound's
// invalid parameters again (ProcessorHooks::before_run); then runs the children in
// sequence (SerialStar). A failed inference fails the node with its reason.
#pragma once

#include "../processor_registry.hpp"
#include "serial_star.hpp"

namespace skillbus::skills {

class InferInvalid : public Processor {
 public:
  explicit InferInvalid(const ProcessorHooks& hooks) : before_run_(hooks.before_run) {}
  State process(const Children& children) override {
    if (!inferred_) {
      inferred_ = true;
      const std::string err =
          before_run_ ? before_run_() : "InferInvalid: only a compound skill's tree has parameters to infer";
      if (!err.empty()) {
        say(err);
        return State::Failure;
      }
    }
    const State s = sequence_.process(children);
    say(sequence_.message());
    return s;
  }
  void reset() override {
    inferred_ = false;
    sequence_.reset();
  }
  std::string name() const override { return "InferInvalid"; }

 private:
  std::function<std::string()> before_run_;
  bool inferred_ = false;
  SerialStar sequence_;
};

}  // namespace skillbus::skills
