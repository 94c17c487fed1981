#include "skill_params.hpp"

#include <algorithm>
#include <set>

#include "conditions.hpp"
#include "grounding.hpp"
#include "param_check.hpp"
#include "skillbus/wm/convert.hpp"

namespace skillbus::skills {

using skillbus_msgs::skill_param_t;

namespace {

// One value's encoding into `buf` (reused: a tick compares every parameter it sent).
const std::vector<uint8_t>& encode_into(const skillbus_msgs::skill_value_t& v, std::vector<uint8_t>& buf) {
  buf.resize(static_cast<size_t>(v.getEncodedSize()));
  v.encode(buf.data(), 0, static_cast<int>(buf.size()));
  return buf;
}

}  // namespace

// Values compared by their encoding: what a skill sent back unchanged. (Value by value:
// each encoding is a whole message, so equal sequences are equal value by value.)
bool same_values(const Param& a, const Param& b) {
  if (a.values.size() != b.values.size()) return false;
  thread_local std::vector<uint8_t> ea, eb;
  for (size_t i = 0; i < a.values.size(); ++i) {
    if (a.values[i].getEncodedSize() != b.values[i].getEncodedSize()) return false;
    if (encode_into(a.values[i], ea) != encode_into(b.values[i], eb)) return false;
  }
  return true;
}

const wm::WorldStore* world_if_ready(TaskContext& ctx) {
  return ctx.world && ctx.world->ready() ? &ctx.world->store() : nullptr;
}

const wm::WorldStore* world_for(TaskContext& ctx, std::string* why) {
  if (!ctx.world) {
    *why = "the manager has no world model";
    return nullptr;
  }
  if (!ctx.world->ensure(std::chrono::milliseconds(1000), why)) return nullptr;
  return &ctx.world->store();
}

namespace {

std::string conditions_error(const char* kind, const std::vector<Condition>& conds, const std::vector<Param>& params,
                             TaskContext& ctx) {
  if (conds.empty()) return "";
  std::string why;
  const wm::WorldStore* world = conditions_need_world(conds) ? world_for(ctx, &why) : world_if_ready(ctx);
  const ConditionResult r = check_conditions(conds, params, world);
  return r.ok ? "" : std::string(kind) + "-condition " + r.failed + " failed" + (why.empty() ? "" : " (" + why + ")");
}

}  // namespace

namespace {

// A required non-element parameter with a value in the description, that the user did
// not give: its value is the description's, written to the blackboard (gather_params).
bool is_static(const Param& decl, const std::string& key, Blackboard& bb) {
  return decl.param_type == skill_param_t::REQUIRED && decl.num_defaults > 0 && decl.data_type != "element" &&
         !bb.given(key);
}

}  // namespace

void write_static_params(const skillbus_msgs::skill_description_t& d, const Scope& scope, Blackboard& bb) {
  for (const auto& decl : d.params) {
    const std::string key = scope.key(decl.key);
    if (scope.specified(decl.key) || !is_static(decl, key, bb)) continue;
    Param p = decl;
    p.values = decl.defaults;  // (as gather_params writes it)
    bb.set(key, p);
  }
}

std::vector<Param> gather_params(const skillbus_msgs::skill_description_t& d, const Scope& scope, Blackboard& bb,
                                 std::string* missing, const wm::WorldStore* world) {
  std::vector<Param> out;
  out.reserve(d.params.size());
  for (const auto& decl : d.params) {
    Param p = decl;
    const std::string key = scope.key(decl.key);
    if (const Param* fixed = scope.specified(decl.key)) {
      p.values = fixed->values;
    } else if (is_static(decl, key, bb)) {
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
      kept.reserve(p.values.size());
      for (auto& v : p.values) {  // (p's own copy: moved, not copied again)
        if (v.type != skillbus_msgs::skill_value_t::ELEMENT || v.element.id.empty()) {
          kept.push_back(std::move(v));
        } else if (const wm::Element* e = world->get(v.element.id)) {
          v.element = wm::to_msg(*e);
          kept.push_back(std::move(v));
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

std::string find_robot(const wm::WorldStore& world, const std::string& label, std::string* id) {
  wm::Query q;
  q.type = "sumo:Agent";  // (the Robot parameter's concept: skiros:Robot and SkiROS2's cora:Robot are below it)
  q.label = label;
  const auto found = world.query(q);
  if (found.size() == 1) {
    *id = found[0]->id;
    return "";
  }
  return found.empty() ? "the world model has no robot (sumo:Agent) labelled '" + label + "' (this manager's --robot)"
                       : "the world model has " + std::to_string(found.size()) + " robots (sumo:Agent) labelled '" +
                             label + "' (this manager's --robot): name one with --robot-element";
}

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
  if (ctx.robot.empty() && !ctx.robot_label.empty()) {
    if (const wm::WorldStore* world = world_if_ready(ctx)) {
      const std::string err = find_robot(*world, ctx.robot_label, &ctx.robot);
      if (!err.empty()) return err;
    }
  }
  for (auto& p : params) {
    if (p.key != "Robot" || p.data_type != "element") continue;
    if (!p.values.empty() && !p.values[0].element.id.empty()) {
      // A manager drives its own robot: another one given (a start, or a compound that
      // specifies it) moved this arm while the skill's conditions and writes named the other.
      if (!ctx.robot.empty() && p.values[0].element.id != ctx.robot)
        return "parameter Robot: " + p.values[0].element.id + " is not the robot this manager drives (" + ctx.robot +
               "; each robot has a manager of its own: skillbus run --robot NAME)";
      continue;
    }
    if (!ctx.robot.empty()) {
      skillbus_msgs::skill_value_t v{};
      v.type = skillbus_msgs::skill_value_t::ELEMENT;
      v.element.id = ctx.robot;
      v.element.type = p.concept;
      p.values = {v};
      p.num_values = 1;
      // On the blackboard, as grounding leaves what it found: the ticks read it there.
      if (!scope.specified(p.key)) bb.set(scope.key(p.key), p);
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

}  // namespace skillbus::skills
