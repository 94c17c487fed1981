// A compound skill node: children ticked by a processor. Its memory (the processor's)
// is cleared when it ends (success, failure or preemption) and when it is reset.
#pragma once

#include "processor.hpp"

namespace skillbus::skills {

class CompoundNode : public Node {
 public:
  CompoundNode(std::string type, std::string label, std::unique_ptr<Processor> processor, Children children = {})
      : Node(std::move(type), std::move(label)), processor_(std::move(processor)), children_(std::move(children)) {}
  void add(std::unique_ptr<Node> child) { children_.push_back(std::move(child)); }
  const Children& children() const override { return children_; }
  std::string processor_name() const override { return processor_->name(); }

 protected:
  State step() override;
  State on_preempt() override;
  void finish() override { processor_->reset(); }
  void on_reset() override { processor_->reset(); }
  // For nodes that learn their children when they start (a compound skill's expansion).
  void install(std::unique_ptr<Processor> processor, Children children) {
    processor_ = std::move(processor);
    children_ = std::move(children);
  }

 private:
  std::unique_ptr<Processor> processor_;
  Children children_;
};

}  // namespace skillbus::skills
