#include "node.hpp"

namespace skillbus::skills {

State Node::tick() {
  if (finished(state_)) reset();
  if (state_ == State::Idle || state_ == State::Uninitialized) {
    if (!start()) {
      state_ = State::Failure;
      if (message_.empty()) message_ = "failed to start";
      finish();
      return state_;
    }
    state_ = State::Running;
  }
  state_ = step();
  if (finished(state_)) finish();
  return state_;
}

void Node::preempt() {
  if (state_ != State::Running) return;
  state_ = on_preempt();
  if (state_ == State::Running) state_ = State::Failure;  // a preempted node ends, whatever its hook says
  finish();
}

State Node::on_preempt() {
  set_result("preempted", skillbus_msgs::skill_state_t::CODE_FAILED);
  return State::Failure;
}

void Node::reset() {
  for (const auto& c : children()) c->reset();
  on_reset();
  state_ = State::Idle;
  message_.clear();
  code_ = 0;
  progress_ = 0;
}

const std::vector<std::unique_ptr<Node>>& Node::children() const {
  static const std::vector<std::unique_ptr<Node>> none;
  return none;
}

void Node::set_result(const std::string& message, int code, double progress) {
  message_ = message;
  code_ = code;
  if (progress >= 0) progress_ = progress;
}

}  // namespace skillbus::skills
