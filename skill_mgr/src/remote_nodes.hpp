// Tree nodes that are skills of skill processes:
//  * RemotePrimitive: each lifecycle step is an RPC tick to the process that serves it
//    (START, EXECUTE, PREEMPT, END), with the node's parameters from the blackboard;
//    the parameters it returns go back to the blackboard.
//  * RemoteCompound: when it starts, asks its process to expand it (RPC expand) and
//    builds its children: placeholders resolve to registered implementations (by type,
//    or type and label), anonymous groups become plain compound nodes.
#pragma once

#include <chrono>
#include <functional>
#include <map>
#include <memory>
#include <string>

#include "blackboard.hpp"
#include "registry.hpp"
#include "skillbus/rpc.hpp"
#include "skillbus_msgs/skill_tick_reply_t.hpp"
#include "skillbus_msgs/skill_tick_t.hpp"
#include "tree/compound.hpp"
#include "world_replica.hpp"

namespace skillbus::skills {

// What the nodes of one task share.
struct TaskContext {
  const Registry& registry;
  Blackboard& blackboard;
  std::function<RpcClient&(const std::string& area)> client;  // one RPC client per skill process
  std::chrono::milliseconds tick_timeout{1000};
  int64_t next_instance = 1;
  WorldReplica* world = nullptr;  // for conditions and grounding
  std::string robot;              // the agent this manager drives: every skill's Robot parameter
  int64_t frame = -1;             // the frame being ticked, passed to skill processes
  int64_t sim_time_ns = 0;
};

// A node's parameters, gathered for a tick: specified by a parent, else static (a
// required parameter with a value in the description), else from the blackboard, else
// an optional parameter's default. `missing` names required parameters without a value.
std::vector<Param> gather_params(const skillbus_msgs::skill_description_t& d, const Scope& scope,
                                 Blackboard& bb, std::string* missing, const wm::WorldStore* world = nullptr);
// At a skill's start: gather, ground abstract element parameters, check pre-conditions.
// Returns "" or why the skill cannot start. With `dry_run` the blackboard is not written
// (choosing among implementations).
std::string prepare_start(TaskContext& ctx, const Implementation& impl, const Scope& scope, std::vector<Param>& params,
                          bool dry_run = false);
// InferInvalid: element parameters of `impl` whose element is gone from the world model
// (or never was concrete) are grounded again and written to the blackboard.
std::string infer_invalid(TaskContext& ctx, const Implementation& impl, const Scope& scope);
// "" or which condition does not hold.
std::string check_hold(TaskContext& ctx, const Implementation& impl, const std::vector<Param>& params);
std::string check_post(TaskContext& ctx, const Implementation& impl, const std::vector<Param>& params);
// Builds the node for an implementation (primitive or compound).
std::unique_ptr<Node> make_skill_node(TaskContext& ctx, const Implementation& impl, std::shared_ptr<Scope> scope);

class RemotePrimitive : public Node {
 public:
  RemotePrimitive(TaskContext& ctx, Implementation impl, std::shared_ptr<Scope> scope);
  const std::vector<Param>& last_params() const { return params_; }

 protected:
  bool start() override;
  State step() override;
  State on_preempt() override;
  void finish() override;

 private:
  State call(int8_t action);
  TaskContext& ctx_;
  Implementation impl_;
  std::shared_ptr<Scope> scope_;
  std::vector<Param> params_;
  int64_t instance_ = 0;
  int64_t incarnation_ = 0;  // of the skill process that runs this instance
  bool first_ = true;
  bool unresponsive_ = false;  // its process did not answer: do not wait for it again
  int64_t wm_version_ = -1;    // the world version the skill has seen (from its last reply)
};

// A placeholder without a label whose type has several implementations: at start it
// takes the first (label order) that can start (its parameters ground and its
// pre-conditions hold), and runs it.
class Alternatives : public Node {
 public:
  Alternatives(TaskContext& ctx, std::vector<Implementation> impls, std::shared_ptr<Scope> scope);
  const Children& children() const override { return chosen_; }

 protected:
  bool start() override;
  State step() override { return chosen_.front()->tick(); }
  State on_preempt() override;
  void on_reset() override { chosen_.clear(); }

 private:
  TaskContext& ctx_;
  std::vector<Implementation> impls_;
  std::shared_ptr<Scope> scope_;
  Children chosen_;
};

// An anonymous group under InferInvalid: infers its compound's invalid parameters when it
// starts, then runs its children in sequence.
class InferGroup : public CompoundNode {
 public:
  InferGroup(TaskContext& ctx, Implementation owner, std::shared_ptr<Scope> scope);

 protected:
  bool start() override;

 private:
  TaskContext& ctx_;
  Implementation owner_;
  std::shared_ptr<Scope> scope_;
};

class RemoteCompound : public CompoundNode {
 public:
  RemoteCompound(TaskContext& ctx, Implementation impl, std::shared_ptr<Scope> scope);

 protected:
  bool start() override;
  State step() override;

 private:
  TaskContext& ctx_;
  Implementation impl_;
  std::shared_ptr<Scope> scope_;
};

}  // namespace skillbus::skills
