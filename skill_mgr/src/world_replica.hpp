// The skill manager's copy of the world model, for condition checks and grounding:
// the same WorldStore as the server's, filled from a paged snapshot (RPC wm.snapshot)
// and kept current by SB_WM_CHANGES (delivered by the lockstep participant, so in
// canonical order under lockstep). A gap in versions or a scene load triggers a resync.
// Without a world model server the replica stays empty and says so.
#pragma once

#include <memory>
#include <string>
#include <vector>

#include "skillbus/lockstep.hpp"
#include "skillbus/rpc.hpp"
#include "skillbus_msgs/wm_change_t.hpp"
#include "skillbus/wm/ontology.hpp"
#include "skillbus/wm/rdf.hpp"
#include "skillbus/wm/store.hpp"

namespace skillbus::skills {

class WorldReplica {
 public:
  // Subscribes to the change stream through `participant`. Without ontology files the
  // ontology is the world model server's (RPC wm.ontology), read with each full resync.
  WorldReplica(Bus& bus, LockstepParticipant& participant, const std::vector<std::string>& ontology_files,
               bool wall_clock);
  // Makes sure the replica has been filled once (tries the server for `timeout`).
  // Returns false, with `why`, when no world model server answers.
  bool ensure(std::chrono::milliseconds timeout, std::string* why);
  // Dispatches the bus until the replica has `version` (bounded by `timeout`). Only in
  // wall-clock mode: under lockstep changes arrive at frame boundaries, for everyone alike.
  void wait_for(int64_t version, std::chrono::milliseconds timeout);
  const wm::WorldStore& store() const { return store_; }
  const wm::Ontology& ontology() const { return ontology_; }
  bool ready() const { return ready_; }

 private:
  void resync();
  void on_change(const StampedMessage& m);

  Bus& bus_;
  RpcClient client_;
  wm::Prefixes prefixes_;
  wm::Ontology ontology_;
  wm::WorldStore store_;
  bool ready_ = false;
  bool stale_ = false;
  bool wall_clock_ = false;
  bool ontology_from_server_ = false;
  bool collecting_ = false;                        // a resync is reading pages
  std::vector<skillbus_msgs::wm_change_t> collected_;  // the changes that arrived meanwhile
};

}  // namespace skillbus::skills
