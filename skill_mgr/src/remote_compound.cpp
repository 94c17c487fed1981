#include "remote_compound.hpp"

#include "expansion.hpp"
#include "skill_params.hpp"
#include "skillbus_msgs/skill_state_t.hpp"
#include "skillbus_msgs/skill_tick_t.hpp"
#include "skillbus_msgs/skill_tree_t.hpp"
#include "tree/processor_registry.hpp"

namespace skillbus::skills {

using skillbus_msgs::skill_tick_t;

namespace {
constexpr int kFailed = skillbus_msgs::skill_state_t::CODE_FAILED;
}  // namespace

RemoteCompound::RemoteCompound(TaskContext& ctx, Implementation impl, std::shared_ptr<Scope> scope)
    : CompoundNode(impl.description.type, impl.description.label, make_processor("SerialStar")),
      ctx_(ctx),
      impl_(std::move(impl)),
      scope_(std::move(scope)) {}

State RemoteCompound::step() {
  const auto& d = impl_.description;
  if (d.hold.empty() && d.post.empty()) {
    // Nothing to check: the parameters (each element re-read from the world model) are
    // not gathered at every tick, only what gathering writes to the blackboard is.
    write_static_params(d, *scope_, ctx_.blackboard);
    return CompoundNode::step();
  }
  const auto params = gather_params(d, *scope_, ctx_.blackboard, nullptr, world_if_ready(ctx_));
  const std::string broken = check_hold(ctx_, impl_, params);
  if (!broken.empty()) {
    for (const auto& c : children()) c->preempt();
    set_result(broken, kFailed);
    return State::Failure;
  }
  const State s = CompoundNode::step();
  if (s == State::Success) {
    const std::string unmet = check_post(ctx_, impl_, params);
    if (!unmet.empty()) {
      set_result(unmet, kFailed);
      return State::Failure;
    }
  }
  return s;
}

bool RemoteCompound::start() {
  std::vector<Param> params;
  const std::string err = prepare_start(ctx_, impl_, *scope_, params);
  if (!err.empty()) {
    set_result(err, kFailed);
    return false;
  }
  skill_tick_t t{};
  t.label = impl_.description.label;
  t.action = skill_tick_t::EXPAND;
  t.frame = ctx_.frame;
  t.sim_time_ns = ctx_.sim_time_ns;
  t.params = params;
  t.num_params = static_cast<int32_t>(params.size());
  CallOptions opts;
  opts.timeout = ctx_.expand_timeout;
  skillbus_msgs::skill_tree_t tree;
  try {
    tree = ctx_.client(impl_.rpc_area).call<skillbus_msgs::skill_tree_t>("expand", t, opts);
  } catch (const RpcError& e) {
    set_result("cannot expand " + impl_.description.label + " (process " + impl_.process + "): " + e.what(), kFailed);
    return false;
  }
  if (!tree.error.empty()) {
    set_result(tree.error, kFailed);
    return false;
  }
  Expansion built;
  const std::string bad = build_expansion(ctx_, impl_, scope_, tree, built);
  if (!bad.empty()) {
    set_result(bad, kFailed);
    return false;
  }
  install(std::move(built.processor), std::move(built.top));
  return true;
}

}  // namespace skillbus::skills
