#include "remote_primitive.hpp"

#include <cstdio>

#include "param_check.hpp"
#include "skill_params.hpp"
#include "skillbus_msgs/skill_state_t.hpp"
#include "skillbus_msgs/skill_tick_reply_t.hpp"
#include "skillbus_msgs/skill_tick_t.hpp"

namespace skillbus::skills {

using skillbus_msgs::skill_state_t;
using skillbus_msgs::skill_tick_t;

namespace {

constexpr int kFailed = skill_state_t::CODE_FAILED;

// A state from the wire (a checked reply's: RUNNING, SUCCESS or FAILURE).
State to_state(int8_t s) {
  switch (s) {
    case skill_state_t::RUNNING: return State::Running;
    case skill_state_t::SUCCESS: return State::Success;
    default: return State::Failure;
  }
}

const char* action_name(int8_t action) {
  switch (action) {
    case skill_tick_t::START: return "START";
    case skill_tick_t::EXECUTE: return "EXECUTE";
    case skill_tick_t::PREEMPT: return "PREEMPT";
    case skill_tick_t::END: return "END";
    default: return "tick";
  }
}

// What is wrong with a reply, or "". Acted on, each would go wrong quietly:
// - a parameter the skill does not have, or a value of another type than declared: written
//   to the blackboard, it would reach the skill's siblings (a wrong value becoming another
//   object);
// - a state that is no tick's answer: the skill failed without a reason given;
// - a START or EXECUTE answered RUNNING that says it ended the instance: ticked on, never
//   sent its END (its onEnd never run where the process did not in fact forget it).
std::string wrong_in_reply(const skillbus_msgs::skill_description_t& d, int8_t action,
                          const skillbus_msgs::skill_tick_reply_t& r) {
  if (const std::string bad = check_returned(d, r.params); !bad.empty()) return bad;
  if (action == skill_tick_t::END) return "";  // (its state is not used)
  if (r.state != skill_state_t::RUNNING && r.state != skill_state_t::SUCCESS && r.state != skill_state_t::FAILURE)
    return "state " + std::to_string(r.state) + ", which is not RUNNING, SUCCESS or FAILURE";
  if (r.ended && r.state == skill_state_t::RUNNING && action != skill_tick_t::PREEMPT)
    return "RUNNING and said the same tick ended the instance (onEnd ran): a reply that contradicts itself";
  return "";
}

std::string seconds(std::chrono::milliseconds d) {
  char buf[32];
  std::snprintf(buf, sizeof buf, "%.1f s", static_cast<double>(d.count()) / 1000.0);
  return buf;
}

// The same parameters, values and all, in the same order.
bool same_params(const std::vector<Param>& a, const std::vector<Param>& b) {
  if (a.size() != b.size()) return false;
  for (size_t i = 0; i < a.size(); ++i)
    if (a[i].key != b[i].key || !same_values(a[i], b[i])) return false;
  return true;
}

}  // namespace

RemotePrimitive::RemotePrimitive(TaskContext& ctx, Implementation impl, std::shared_ptr<Scope> scope)
    : Node(impl.description.type, impl.description.label), ctx_(ctx), impl_(std::move(impl)), scope_(std::move(scope)) {}

void RemotePrimitive::set_params(std::vector<Param> params) {
  params_ = std::move(params);
  params_text_stale_ = true;
}

const std::string& RemotePrimitive::last_params_text() const {
  if (params_text_stale_) {
    params_text_ = params_text(params_);
    params_text_stale_ = false;
  }
  return params_text_;
}

bool RemotePrimitive::start() {
  params_text_stale_ = true;
  const std::string err = prepare_start(ctx_, impl_, *scope_, params_);
  if (!err.empty()) {
    set_result(err, kFailed);
    return false;
  }
  instance_ = ctx_.next_instance++;
  incarnation_ = ctx_.registry.incarnation_of(impl_.process);
  first_ = true;
  unresponsive_ = false;
  ended_ = false;
  return true;
}

State RemotePrimitive::call(int8_t action) {
  if (action != skill_tick_t::START && ctx_.registry.incarnation_of(impl_.process) == 0) {
    // The manager dropped the process: it stopped sending heartbeats.
    set_result("skill process " + impl_.process + " stopped answering while running " + impl_.description.label +
                   ": the running skill was lost",
               kFailed);
    return State::Failure;
  }
  if (action != skill_tick_t::START && ctx_.registry.incarnation_of(impl_.process) != incarnation_) {
    // The process announced itself again: it was restarted, and this instance with it.
    set_result("skill process " + impl_.process + " was restarted while running " + impl_.description.label +
                   ": the running skill was lost",
               kFailed);
    return State::Failure;
  }
  if (ctx_.ticks_sent && action >= 0 && action < static_cast<int8_t>(ctx_.ticks_sent->size()))
    ++(*ctx_.ticks_sent)[static_cast<size_t>(action)];
  skill_tick_t t{};
  t.label = impl_.description.label;
  t.instance = instance_;
  t.action = action;
  t.frame = ctx_.frame;
  t.sim_time_ns = ctx_.sim_time_ns;
  t.num_params = static_cast<int32_t>(params_.size());
  t.params = std::move(params_);  // (lent to the request, not copied: back right after the call)
  CallOptions opts;
  opts.timeout = ctx_.tick_timeout;
  opts.retry_interval = std::chrono::milliseconds(100);
  try {
    skillbus_msgs::skill_tick_reply_t reply;
    try {
      reply = ctx_.client(impl_.rpc_area).call<skillbus_msgs::skill_tick_reply_t>("tick", t, opts);
    } catch (...) {
      params_ = std::move(t.params);
      params_text_stale_ = true;
      throw;
    }
    params_ = std::move(t.params);
    params_text_stale_ = true;  // (whatever read the text while they were lent read none)
    if (const std::string wrong = wrong_in_reply(impl_.description, action, reply); !wrong.empty()) {
      // Not trusted to have ended it either: the END that follows the failure ends it
      // where it still runs (and is answered "no running instance" where it does not).
      ended_ = false;
      set_result("skill process " + impl_.process + " answered the " + action_name(action) + " of " +
                     impl_.description.label + " with " + wrong +
                     (reply.message.empty() ? "" : " (its message: " + reply.message + ")"),
                 kFailed);
      return State::Failure;
    }
    set_result(reply.message, reply.code, reply.progress);
    wm_version_ = reply.wm_version;
    // What the skill wrote (or saw) is in the replica before anything after this tick
    // reads the world: its post-conditions, and the next skill's element parameters, which
    // are read from the replica (outside lockstep the change stream may lag the skill's
    // commit reply; on DDS the next skill was handed the element as it was before).
    if (ctx_.world && ctx_.world->ready() && wm_version_ > ctx_.world->store().version())
      ctx_.world->wait_for(wm_version_, std::chrono::milliseconds(1000));
    ended_ = reply.ended;
    idle_until_ns_ = reply.state == skill_state_t::RUNNING ? reply.idle_until_ns : 0;
    // What the skill changed goes to the blackboard, an emptied value included; what it
    // sent back unchanged is not written (a parallel sibling may have written that key).
    for (const auto& p : reply.params) {
      if (scope_->specified(p.key)) continue;
      const Param* sent = nullptr;
      for (const auto& q : params_)
        if (q.key == p.key) sent = &q;
      if (sent && same_values(*sent, p)) continue;
      ctx_.blackboard.set(scope_->key(p.key), p);
    }
    if (!reply.params.empty()) set_params(std::move(reply.params));
    return to_state(reply.state);
  } catch (const RpcTimeout&) {
    unresponsive_ = true;
    set_result("skill process " + impl_.process + " did not answer the tick of " + impl_.description.label +
                   " within " + seconds(ctx_.tick_timeout),
               kFailed);
  } catch (const RpcError& e) {
    set_result("skill process " + impl_.process + " failed the tick of " + impl_.description.label + ": " + e.what(),
               kFailed);
  }
  return State::Failure;
}

State RemotePrimitive::step() {
  std::vector<Param> now = gather_params(impl_.description, *scope_, ctx_.blackboard, nullptr, world_if_ready(ctx_));
  // A skill idle until later (idle_until_ns) is not ticked while what it would be given is
  // what it answered with; a changed parameter reaches it at once, and so does the loss of
  // its process (dropped for its silence, or started again: call() names it).
  const bool idle = !first_ && ctx_.sim_time_ns < idle_until_ns_ &&
                    ctx_.registry.incarnation_of(impl_.process) == incarnation_ && same_params(now, params_);
  if (!idle) set_params(std::move(now));
  if (!first_) {  // hold-conditions, checked on every later tick (the first was checked at start)
    const std::string broken = check_hold(ctx_, impl_, params_);
    if (!broken.empty()) {
      call(skill_tick_t::PREEMPT);
      set_result(broken, kFailed);
      return State::Failure;
    }
  }
  if (idle) {
    if (ctx_.idle_ticks) ++*ctx_.idle_ticks;
    return State::Running;  // (its message, code and progress stay those of its last tick)
  }
  const int8_t action = first_ ? skill_tick_t::START : skill_tick_t::EXECUTE;
  first_ = false;
  const State s = call(action);
  if (s == State::Success) {  // (the replica has the skill's writes: call)
    const std::string unmet = check_post(ctx_, impl_, params_);
    if (!unmet.empty()) {
      set_result(unmet, kFailed);
      return State::Failure;
    }
  }
  return s;
}

State RemotePrimitive::on_preempt() {
  if (unresponsive_) return State::Failure;
  const State s = call(skill_tick_t::PREEMPT);
  return s == State::Running ? State::Failure : s;
}

void RemotePrimitive::finish() {
  // The tick that finished it, or its PREEMPT, ended the instance in the skill process
  // (onEnd, as SkiROS2 within that tick): nothing left to send.
  if (ended_) instance_ = 0;
  if (instance_ == 0 || unresponsive_) return;
  const std::string msg = message();
  const int c = code();
  call(skill_tick_t::END);
  set_result(msg, c);  // the end does not overwrite the result
  instance_ = 0;
}

}  // namespace skillbus::skills
