#include "compound.hpp"

namespace skillbus::skills {

State CompoundNode::step() {
  if (children_.empty()) {
    set_result("no children");
    return State::Success;
  }
  const State s = processor_->process(children_);
  set_result(processor_->message());
  return s;
}

State CompoundNode::on_preempt() {
  for (const auto& c : children_) c->preempt();
  set_result("preempted", skillbus_msgs::skill_state_t::CODE_FAILED);
  return State::Failure;
}

}  // namespace skillbus::skills
