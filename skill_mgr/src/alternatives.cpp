#include "alternatives.hpp"

#include "skill_nodes.hpp"
#include "skill_params.hpp"
#include "skillbus_msgs/skill_state_t.hpp"

namespace skillbus::skills {

namespace {
constexpr int kFailed = skillbus_msgs::skill_state_t::CODE_FAILED;
}  // namespace

Alternatives::Alternatives(TaskContext& ctx, std::vector<Implementation> impls, std::shared_ptr<Scope> scope)
    : Node(impls.front().description.type, ""), ctx_(ctx), impls_(std::move(impls)), scope_(std::move(scope)) {}

bool Alternatives::start() {
  std::string first_error;
  for (const auto& impl : impls_) {
    std::vector<Param> params;
    const std::string err = prepare_start(ctx_, impl, *scope_, params, true);
    if (err.empty()) {
      chosen_.clear();
      chosen_.push_back(make_skill_node(ctx_, impl, scope_));
      set_result("chose " + impl.description.label);
      return true;
    }
    if (first_error.empty()) first_error = impl.description.label + ": " + err;
  }
  set_result(first_error + " (none of " + std::to_string(impls_.size()) + " implementations of " + type() + " can start)",
             kFailed);
  return false;
}

State Alternatives::on_preempt() {
  for (const auto& c : chosen_) c->preempt();
  set_result("preempted", kFailed);
  return State::Failure;
}

}  // namespace skillbus::skills
