#include "remote_nodes.hpp"

#include <algorithm>
#include <cstdio>

#include "convert.hpp"
#include "grounding.hpp"
#include "param_check.hpp"
#include "skillbus_msgs/skill_tree_t.hpp"

namespace skillbus::skills {

using skillbus_msgs::skill_param_t;
using skillbus_msgs::skill_tick_t;

namespace {

State to_state(int8_t s) {
  switch (s) {
    case 2: return State::Running;
    case 3: return State::Success;
    default: return State::Failure;
  }
}

// Values compared by their encoding: what a skill sent back unchanged.
std::vector<uint8_t> encoded(const Param& p) {
  std::vector<uint8_t> out;
  for (const auto& v : p.values) {
    std::vector<uint8_t> buf(static_cast<size_t>(v.getEncodedSize()));
    v.encode(buf.data(), 0, static_cast<int>(buf.size()));
    out.insert(out.end(), buf.begin(), buf.end());
  }
  return out;
}

// "" or which remap or specify key of a tree node the child skill does not have.
std::string unknown_keys(const skillbus_msgs::skill_description_t& d, const skillbus_msgs::skill_tree_node_t& n) {
  auto has = [&d](const std::string& key) {
    for (const auto& p : d.params)
      if (p.key == key) return true;
    return false;
  };
  std::string keys;
  for (const auto& p : d.params) keys += (keys.empty() ? "" : ", ") + p.key;
  for (int r = 0; r < n.num_remaps && r < static_cast<int>(n.remap_from.size()); ++r)
    if (!has(n.remap_from[r]))
      return "remap " + n.remap_from[r] + " -> " + n.remap_to[r] + ": " + d.type + " has no parameter " +
             n.remap_from[r] + " (it has: " + keys + ")";
  for (const auto& sp : n.specify)
    if (!has(sp.key)) return "specify " + sp.key + ": " + d.type + " has no parameter " + sp.key + " (it has: " + keys + ")";
  return "";
}

bool same_values(const Param& a, const Param& b) {
  return a.values.size() == b.values.size() && encoded(a) == encoded(b);
}

std::string seconds(std::chrono::milliseconds d) {
  char buf[32];
  std::snprintf(buf, sizeof buf, "%.1f s", static_cast<double>(d.count()) / 1000.0);
  return buf;
}

}  // namespace

std::vector<Param> gather_params(const skillbus_msgs::skill_description_t& d, const Scope& scope, Blackboard& bb,
                                 std::string* missing, const wm::WorldStore* world) {
  std::vector<Param> out;
  for (const auto& decl : d.params) {
    Param p = decl;
    const std::string key = scope.key(decl.key);
    if (const Param* fixed = scope.specified(decl.key)) {
      p.values = fixed->values;
    } else if (decl.param_type == skill_param_t::REQUIRED && decl.num_defaults > 0 && decl.data_type != "element" &&
               !bb.given(key)) {
      p.values = decl.defaults;  // static: overwrites the blackboard every run, unless the user gave it
      bb.set(key, p);
    } else if (bb.has(key)) {
      p.values = bb.get(key)->values;
    } else if (decl.num_defaults > 0) {
      p.values = decl.defaults;  // a default, or (for now) an abstract element to ground
    } else {
      p.values.clear();
    }
    if (world) {  // element parameters are re-read from the world model; a deleted one is dropped
      std::vector<skillbus_msgs::skill_value_t> kept;
      for (auto& v : p.values) {
        if (v.type != skillbus_msgs::skill_value_t::ELEMENT || v.element.id.empty()) {
          kept.push_back(v);
        } else if (const wm::Element* e = world->get(v.element.id)) {
          v.element = wm::to_msg(*e);
          kept.push_back(v);
        }
      }
      p.values = std::move(kept);
    }
    p.num_values = static_cast<int32_t>(p.values.size());
    if (missing && missing->empty() && decl.param_type == skill_param_t::REQUIRED && p.values.empty())
      *missing = "missing parameter " + decl.key + (key != decl.key ? " (blackboard key " + key + ")" : "") + " of " +
                 d.type;
    out.push_back(std::move(p));
  }
  return out;
}

namespace {

const wm::WorldStore* world_if_ready(TaskContext& ctx) {
  return ctx.world && ctx.world->ready() ? &ctx.world->store() : nullptr;
}

// The world, fetched when the conditions or grounding need it; null, with `why`, without one.
const wm::WorldStore* world_for(TaskContext& ctx, std::string* why) {
  if (!ctx.world) {
    *why = "the manager has no world model";
    return nullptr;
  }
  if (!ctx.world->ensure(std::chrono::milliseconds(1000), why)) return nullptr;
  return &ctx.world->store();
}

std::string conditions_error(const char* kind, const std::vector<Condition>& conds, const std::vector<Param>& params,
                             TaskContext& ctx) {
  if (conds.empty()) return "";
  std::string why;
  const wm::WorldStore* world = conditions_need_world(conds) ? world_for(ctx, &why) : world_if_ready(ctx);
  const ConditionResult r = check_conditions(conds, params, world);
  return r.ok ? "" : std::string(kind) + "-condition " + r.failed + " failed" + (why.empty() ? "" : " (" + why + ")");
}

}  // namespace

std::string prepare_start(TaskContext& ctx, const Implementation& impl, const Scope& scope, std::vector<Param>& params,
                          bool dry_run) {
  Blackboard scratch = ctx.blackboard;  // a dry run must leave the task's blackboard alone
  Blackboard& bb = dry_run ? scratch : ctx.blackboard;
  std::string missing;
  params = gather_params(impl.description, scope, bb, &missing, nullptr);
  // Robot (added to every description): the manager's own agent when it was given one;
  // else grounded like the rest, but only from a world model that is already there, so
  // that skills run without a world model when nothing else needs one.
  std::set<std::string> skip;
  std::vector<std::string> unchecked;  // the manager's own Robot, when there is no world to check it in
  for (auto& p : params) {
    if (p.key != "Robot" || p.data_type != "element" || (!p.values.empty() && !p.values[0].element.id.empty())) continue;
    if (!ctx.robot.empty()) {
      skillbus_msgs::skill_value_t v{};
      v.type = skillbus_msgs::skill_value_t::ELEMENT;
      v.element.id = ctx.robot;
      v.element.type = p.concept;
      p.values = {v};
      p.num_values = 1;
      if (!world_if_ready(ctx)) unchecked.push_back(p.key);
    } else if (!world_if_ready(ctx)) {
      skip.insert(p.key);
    }
  }
  // Every concrete element must be in the world and of the parameter's concept: a wrong
  // id fails the start here, before grounding could mistake it for an abstract value.
  bool concrete = false;
  for (const auto& p : params)
    for (const auto& v : p.values)
      concrete |= concrete_element(v) && std::find(unchecked.begin(), unchecked.end(), p.key) == unchecked.end();
  if (concrete) {
    std::string why;
    const wm::WorldStore* world = world_for(ctx, &why);
    if (!world) return "cannot check the element parameters of " + impl.description.type + ": " + why;
    const std::string err = check_elements(params, *world, unchecked);
    if (!err.empty()) return err + " (" + impl.description.type + ")";
  }
  if (needs_grounding(params, skip)) {
    std::string why;
    const wm::WorldStore* world = world_for(ctx, &why);
    if (!world) return "cannot ground the parameters of " + impl.description.type + ": " + why;
    const std::string err = ground(params, impl.description.pre, *world, skip);
    if (!err.empty()) return err;
    for (const auto& p : params)  // what grounding found is on the blackboard for the next skills
      if (!scope.specified(p.key) && !p.values.empty()) bb.set(scope.key(p.key), p);
    missing.clear();
    gather_params(impl.description, scope, bb, &missing, nullptr);
  }
  if (!missing.empty()) return missing;
  const std::string pre = conditions_error("pre", impl.description.pre, params, ctx);
  if (!pre.empty()) return pre;
  // A hold-condition that is already false would stop the skill at its first check:
  // stop it before it acts at all.
  return conditions_error("hold", impl.description.hold, params, ctx);
}

std::string infer_invalid(TaskContext& ctx, const Implementation& impl, const Scope& scope) {
  std::string why;
  const wm::WorldStore* world = world_for(ctx, &why);
  if (!world) return "InferInvalid: " + why;
  std::vector<Param> params = gather_params(impl.description, scope, ctx.blackboard, nullptr, nullptr);
  // Invalid: an element that is gone (or was never concrete), or one that a failing
  // pre-condition is about (e.g. the cube of the last round, now in the bin).
  std::set<std::string> suspect;
  for (const auto& c : impl.description.pre)
    if (!check_conditions({c}, params, world).ok)
      for (const auto* k : {&c.subject, &c.object})
        if (!k->empty() && !scope.specified(*k)) suspect.insert(*k);
  std::set<std::string> valid;
  for (auto& p : params) {
    if (p.data_type != "element") {
      valid.insert(p.key);
      continue;
    }
    const bool ok = !p.values.empty() && !p.values[0].element.id.empty() && world->get(p.values[0].element.id) &&
                    !suspect.count(p.key);
    if (ok) {
      valid.insert(p.key);
    } else {
      skillbus_msgs::skill_value_t v{};  // forget the stale element: ground it like a new one
      v.type = skillbus_msgs::skill_value_t::ELEMENT;
      v.element.type = p.concept;
      for (const auto& decl : impl.description.params)  // the description's label, not the stale element's
        if (decl.key == p.key && !decl.defaults.empty()) v.element.label = decl.defaults[0].element.label;
      p.values = {v};
      p.num_values = 1;
      p.param_type = skill_param_t::REQUIRED;
    }
  }
  if (valid.size() == params.size()) return "";
  const std::string err = ground(params, impl.description.pre, *world, valid);
  if (!err.empty()) return "InferInvalid: " + err;
  for (const auto& p : params)
    if (!valid.count(p.key) && !scope.specified(p.key)) ctx.blackboard.set(scope.key(p.key), p);
  return "";
}

std::string check_hold(TaskContext& ctx, const Implementation& impl, const std::vector<Param>& params) {
  return conditions_error("hold", impl.description.hold, params, ctx);
}

std::string check_post(TaskContext& ctx, const Implementation& impl, const std::vector<Param>& params) {
  return conditions_error("post", impl.description.post, params, ctx);
}

std::unique_ptr<Node> make_skill_node(TaskContext& ctx, const Implementation& impl, std::shared_ptr<Scope> scope) {
  if (impl.description.compound) return std::make_unique<RemoteCompound>(ctx, impl, std::move(scope));
  return std::make_unique<RemotePrimitive>(ctx, impl, std::move(scope));
}

// ---------------------------------------------------------------- primitive

RemotePrimitive::RemotePrimitive(TaskContext& ctx, Implementation impl, std::shared_ptr<Scope> scope)
    : Node(impl.description.type, impl.description.label), ctx_(ctx), impl_(std::move(impl)), scope_(std::move(scope)) {}

bool RemotePrimitive::start() {
  const std::string err = prepare_start(ctx_, impl_, *scope_, params_);
  if (!err.empty()) {
    set_result(err, -1);
    return false;
  }
  instance_ = ctx_.next_instance++;
  incarnation_ = ctx_.registry.incarnation_of(impl_.process);
  first_ = true;
  unresponsive_ = false;
  return true;
}

State RemotePrimitive::call(int8_t action) {
  if (action != skill_tick_t::START && ctx_.registry.incarnation_of(impl_.process) == 0) {
    // The manager dropped the process: it stopped sending heartbeats.
    set_result("skill process " + impl_.process + " stopped answering while running " + impl_.description.label +
                   ": the running skill was lost",
               -1);
    return State::Failure;
  }
  if (action != skill_tick_t::START && ctx_.registry.incarnation_of(impl_.process) != incarnation_) {
    // The process announced itself again: it was restarted, and this instance with it.
    set_result("skill process " + impl_.process + " was restarted while running " + impl_.description.label +
                   ": the running skill was lost",
               -1);
    return State::Failure;
  }
  skill_tick_t t{};
  t.label = impl_.description.label;
  t.instance = instance_;
  t.action = action;
  t.frame = ctx_.frame;
  t.sim_time_ns = ctx_.sim_time_ns;
  t.params = params_;
  t.num_params = static_cast<int32_t>(params_.size());
  CallOptions opts;
  opts.timeout = ctx_.tick_timeout;
  opts.retry_interval = std::chrono::milliseconds(100);
  try {
    const auto reply = ctx_.client(impl_.rpc_area).call<skillbus_msgs::skill_tick_reply_t>("tick", t, opts);
    set_result(reply.message, reply.code, reply.progress);
    wm_version_ = reply.wm_version;
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
    if (!reply.params.empty()) params_ = reply.params;
    return to_state(reply.state);
  } catch (const RpcTimeout&) {
    unresponsive_ = true;
    set_result("skill process " + impl_.process + " did not answer the tick of " + impl_.description.label +
                   " within " + seconds(ctx_.tick_timeout),
               -1);
  } catch (const RpcError& e) {
    set_result("skill process " + impl_.process + " failed the tick of " + impl_.description.label + ": " + e.what(),
               -1);
  }
  return State::Failure;
}

State RemotePrimitive::step() {
  params_ = gather_params(impl_.description, *scope_, ctx_.blackboard, nullptr, world_if_ready(ctx_));
  if (!first_) {  // hold-conditions, checked on every later tick (the first was checked at start)
    const std::string broken = check_hold(ctx_, impl_, params_);
    if (!broken.empty()) {
      call(skill_tick_t::PREEMPT);
      set_result(broken, -1);
      return State::Failure;
    }
  }
  const int8_t action = first_ ? skill_tick_t::START : skill_tick_t::EXECUTE;
  first_ = false;
  const State s = call(action);
  if (s == State::Success) {
    // The skill's own last writes must be in the replica before its post-conditions are
    // judged (outside lockstep the change stream may lag the skill's commit reply).
    if (ctx_.world && wm_version_ >= 0 && !impl_.description.post.empty())
      ctx_.world->wait_for(wm_version_, std::chrono::milliseconds(1000));
    const std::string unmet = check_post(ctx_, impl_, params_);
    if (!unmet.empty()) {
      set_result(unmet, -1);
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
  if (instance_ == 0 || unresponsive_) return;
  const std::string msg = message();
  const int c = code();
  call(skill_tick_t::END);
  set_result(msg, c);  // the end does not overwrite the result
  instance_ = 0;
}

// ---------------------------------------------------------------- alternatives

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
             -1);
  return false;
}

State Alternatives::on_preempt() {
  for (const auto& c : chosen_) c->preempt();
  set_result("preempted", -1);
  return State::Failure;
}

InferGroup::InferGroup(TaskContext& ctx, Implementation owner, std::shared_ptr<Scope> scope)
    : CompoundNode("", "", make_processor("SerialStar")), ctx_(ctx), owner_(std::move(owner)), scope_(std::move(scope)) {}

bool InferGroup::start() {
  const std::string err = infer_invalid(ctx_, owner_, *scope_);
  if (!err.empty()) {
    set_result(err, -1);
    return false;
  }
  return true;
}

// ---------------------------------------------------------------- compound

RemoteCompound::RemoteCompound(TaskContext& ctx, Implementation impl, std::shared_ptr<Scope> scope)
    : CompoundNode(impl.description.type, impl.description.label, make_processor("SerialStar")),
      ctx_(ctx),
      impl_(std::move(impl)),
      scope_(std::move(scope)) {}

State RemoteCompound::step() {
  const auto params = gather_params(impl_.description, *scope_, ctx_.blackboard, nullptr, world_if_ready(ctx_));
  const std::string broken = check_hold(ctx_, impl_, params);
  if (!broken.empty()) {
    for (const auto& c : children()) c->preempt();
    set_result(broken, -1);
    return State::Failure;
  }
  const State s = CompoundNode::step();
  if (s == State::Success) {
    const std::string unmet = check_post(ctx_, impl_, params);
    if (!unmet.empty()) {
      set_result(unmet, -1);
      return State::Failure;
    }
  }
  return s;
}

bool RemoteCompound::start() {
  std::vector<Param> params;
  const std::string err = prepare_start(ctx_, impl_, *scope_, params);
  if (!err.empty()) {
    set_result(err, -1);
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
  opts.timeout = ctx_.tick_timeout;
  skillbus_msgs::skill_tree_t tree;
  try {
    tree = ctx_.client(impl_.rpc_area).call<skillbus_msgs::skill_tree_t>("expand", t, opts);
  } catch (const RpcError& e) {
    set_result("cannot expand " + impl_.description.label + " (process " + impl_.process + "): " + e.what(), -1);
    return false;
  }
  if (!tree.error.empty() || tree.nodes.empty()) {
    set_result(tree.error.empty() ? "expand of " + impl_.description.label + " gave no tree" : tree.error, -1);
    return false;
  }
  // Build the nodes in preorder; each non-root node goes under its parent.
  std::vector<CompoundNode*> groups(tree.nodes.size(), nullptr);
  std::vector<std::shared_ptr<Scope>> scopes(tree.nodes.size());
  scopes[0] = scope_;
  Children top;
  for (size_t i = 1; i < tree.nodes.size(); ++i) {
    const auto& n = tree.nodes[i];
    if (n.parent < 0 || static_cast<size_t>(n.parent) >= i) {
      set_result("expand of " + impl_.description.label + ": node " + std::to_string(i) + " has no valid parent", -1);
      return false;
    }
    std::map<std::string, std::string> remap;
    for (int r = 0; r < n.num_remaps && r < static_cast<int>(n.remap_to.size()); ++r) remap[n.remap_from[r]] = n.remap_to[r];
    std::map<std::string, Param> specify;
    for (const auto& sp : n.specify) specify[sp.key] = sp;
    scopes[i] = scopes[n.parent]->child(std::move(remap), std::move(specify));
    std::unique_ptr<Node> node;
    try {
      if (n.type.empty()) {
        std::unique_ptr<CompoundNode> group;
        if (n.processor == "InferInvalid")
          group = std::make_unique<InferGroup>(ctx_, impl_, scopes[i]);
        else
          group = std::make_unique<CompoundNode>("", "", make_processor(n.processor));
        groups[i] = group.get();
        node = std::move(group);
      } else {
        auto impls = ctx_.registry.find(n.type, n.label);
        if (impls.empty()) {
          const std::string gone = ctx_.registry.gone(n.type);
          set_result("no skill of type " + n.type + (n.label.empty() ? "" : " with label " + n.label) +
                         " is available (in " + impl_.description.label + ")" + (gone.empty() ? "" : ": " + gone),
                     -1);
          return false;
        }
        // A remap or specify of a key the child does not have would be ignored silently
        // (SkiROS2 does): a typo in a tree is an error that names it.
        const std::string bad = unknown_keys(impls.front()->description, n);
        if (!bad.empty()) {
          set_result("expand of " + impl_.description.label + ": " + bad, -1);
          return false;
        }
        if (impls.size() > 1 && n.label.empty()) {
          std::vector<Implementation> copies;
          for (const auto* x : impls) copies.push_back(*x);
          node = std::make_unique<Alternatives>(ctx_, std::move(copies), scopes[i]);
        } else {
          node = make_skill_node(ctx_, *impls.front(), scopes[i]);
        }
      }
    } catch (const std::invalid_argument& e) {
      set_result("expand of " + impl_.description.label + ": " + e.what(), -1);
      return false;
    }
    if (n.parent == 0)
      top.push_back(std::move(node));
    else if (groups[n.parent])
      groups[n.parent]->add(std::move(node));
    else {
      set_result("expand of " + impl_.description.label + ": node " + std::to_string(i) + " has a skill as parent", -1);
      return false;
    }
  }
  try {
    std::string proc = tree.nodes[0].processor;
    if (proc == "InferInvalid") {  // infer the compound's invalid parameters, then run in sequence
      const std::string inferred = infer_invalid(ctx_, impl_, *scope_);
      if (!inferred.empty()) {
        set_result(inferred, -1);
        return false;
      }
      proc = "SerialStar";
    }
    install(make_processor(proc), std::move(top));
  } catch (const std::invalid_argument& e) {
    set_result("expand of " + impl_.description.label + ": " + e.what(), -1);
    return false;
  }
  return true;
}

}  // namespace skillbus::skills
