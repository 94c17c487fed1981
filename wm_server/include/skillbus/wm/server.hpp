// The world model server process (see wm_server/README.md for its channels and RPCs).
#pragma once

#include <chrono>
#include <deque>
#include <map>
#include <memory>
#include <string>
#include <vector>

#include "skillbus/lockstep.hpp"
#include "skillbus/rpc.hpp"
#include "skillbus/wm/journal.hpp"
#include "skillbus/wm/ontology_files.hpp"
#include "skillbus/wm/ontology.hpp"
#include "skillbus/wm/rdf.hpp"
#include "skillbus/wm/sparql.hpp"
#include "skillbus/wm/store.hpp"
#include "skillbus_msgs/wm_change_t.hpp"
#include "skillbus_msgs/wm_commit_t.hpp"
#include "skillbus_msgs/wm_elements_t.hpp"
#include "skillbus_msgs/wm_lock_t.hpp"
#include "skillbus_msgs/wm_query_t.hpp"
#include "skillbus_msgs/wm_scene_t.hpp"
#include "skillbus_msgs/wm_transform_t.hpp"
#include "skillbus_msgs/wm_txn_t.hpp"

namespace skillbus::wm {

struct ServerOptions {
  std::string data_dir = "wm_data";
  std::vector<std::string> ontology_files;  // Turtle/OWL files, loaded in order
  std::vector<std::string> ontology_library;  // files found by the IRI they declare when something imports it
  std::string scene_file;                   // loaded at start when the data directory is empty
  std::string name = "wm";                  // lockstep participant name
  bool wall_clock = false;
  int64_t frame_period_ns = 10'000'000;     // wall-clock mode
  long snapshot_every = 1000;               // commits between snapshots
  size_t recent_memory = 4096;              // transactions remembered for exactly-once
  long crash_after_commits = -1;            // tests: die (_exit) after this many durable commits, before replying
  int64_t hold_changes_ns = 0;              // tests, wall clock: publish each change this long after it (a slow change stream)
  // The largest reply of get, query and snapshot, encoded: a larger one is refused,
  // naming paging. An LCM message over UDP is lost whole with any of its 64 KB
  // fragments, and a default receive buffer (208 KB) holds about three of them.
  size_t max_reply_bytes = 128 * 1024;
  // The RPC server's memory of replies (answering retries) is bounded by bytes too.
  size_t rpc_memory_bytes = 16 * 1024 * 1024;
  // A SPARQL query's work: the candidate triples its patterns may look at (SparqlEngine).
  uint64_t sparql_max_examined = SparqlEngine::kMaxExamined;
};

class WorldModelServer {
 public:
  WorldModelServer(Bus& bus, ServerOptions options);
  // Runs until the lockstep master ends the run, or `should_stop` says so (checked every frame).
  RunResult run_until(std::function<bool()> should_stop);
  const WorldStore& store() const { return store_; }
  Journal& journal() { return journal_; }
  std::string startup_report() const { return startup_report_; }
  long rejected() const { return rejected_; }

 private:
  skillbus_msgs::wm_commit_t commit(skillbus_msgs::wm_txn_t txn);
  // Which relations a reply carries: every relation touching its elements (get, query),
  // or only those whose object is one of them (snapshot pages: each relation comes once,
  // with its object's page; by subject or touching, a container's thousand skiros:contain
  // relations would all go into its page, which no bound on a reply could take).
  enum class Relations { Touching, ByObject };
  skillbus_msgs::wm_elements_t elements_reply(const std::vector<const Element*>& found, bool ids_only,
                                              const char* method, Relations relations) const;
  [[noreturn]] void too_large(const char* method, size_t fitted, size_t found) const;
  skillbus_msgs::wm_elements_t on_get(const skillbus_msgs::wm_query_t& q) const;
  skillbus_msgs::wm_elements_t on_query(const skillbus_msgs::wm_query_t& q, const char* method,
                                        Relations relations) const;
  skillbus_msgs::wm_scene_t on_load_scene(const skillbus_msgs::wm_scene_t& req);
  skillbus_msgs::wm_scene_t on_save_scene(const skillbus_msgs::wm_scene_t& req) const;
  std::string scene_path(const std::string& name) const;  // DATA/scenes/NAME.ttl, names only
  skillbus_msgs::wm_transform_t on_transform(const skillbus_msgs::wm_transform_t& req) const;
  void on_txn_message(const StampedMessage& m);
  void on_frame(int64_t frame, int64_t sim_time_ns);
  void recover();
  void remember(const skillbus_msgs::wm_commit_t& c);
  void snapshot(bool in_background);
  void load_scene_text(const std::string& text, const std::string& source, std::string* report);
  // The ontology's RPCs (server_ontology.cpp): ontology, sparql, add_axioms, lock.
  void add_ontology_methods();
  skillbus_msgs::wm_scene_t on_add_axioms(const skillbus_msgs::wm_scene_t& req);
  skillbus_msgs::wm_lock_t on_lock(const skillbus_msgs::wm_lock_t& req);
  std::vector<Triple> all_axioms() const;  // the ontology's files, the scene's imports and axioms
  // A scene load or new axioms: the world goes to the next version with a new ontology
  // and new scene triples (and, for a load, new elements), made durable before the reply
  // (the scene files of that version, then its snapshot; journal.hpp). What cannot be
  // made durable changes nothing, and throws WmError.
  struct SceneChange {
    std::string what;  // "the scene", for errors
    Ontology ontology;
    Prefixes prefixes;
    std::vector<Triple> imports, extra;
    bool new_world = false;  // a load: the world becomes these elements and relations
    std::vector<Element> elements;
    std::vector<Relation> relations;
  };
  void change_scene(SceneChange change);
  // Replicas read the world again (and the skill manager the ontology): a change that
  // says "reset" at the new version of a scene change.
  void announce_reset();

  Bus& bus_;
  ServerOptions opt_;
  Prefixes prefixes_;
  bool snapshot_on_disk(int64_t version) const;  // DATA/snapshot.bin is whole and at `version`
  Ontology ontology_;
  Ontology base_ontology_;  // the --ontology files and what they import: where a scene load starts
  WorldStore store_;
  Journal journal_;
  LockstepParticipant participant_;
  RpcServer rpc_;
  std::map<std::string, skillbus_msgs::wm_commit_t> recent_;  // "client\nrequest" -> result
  std::map<std::string, int64_t> last_request_;  // client -> the highest request id answered (kept past recent_)
  std::deque<std::string> recent_order_;
  std::vector<skillbus_msgs::wm_change_t> pending_changes_;
  std::deque<std::pair<std::chrono::steady_clock::time_point, skillbus_msgs::wm_change_t>> held_changes_;  // hold_changes_ns
  void publish_change_now(skillbus_msgs::wm_change_t change);  // (wall clock)
  std::vector<skillbus_msgs::wm_commit_t> pending_results_;
  std::string startup_report_;
  std::string ontology_report_;  // what was loaded from --ontology
  std::vector<Triple> ontology_triples_;  // as loaded from --ontology (the RPC ontology answers them)
  std::vector<Triple> scene_extra_;  // the loaded scene's triples that are no elements (Scene::extra)
  OntologyLibrary library_;
  std::vector<Triple> scene_imports_;  // the ontologies the loaded scene imported from library_
  std::string lock_holder_;            // wm.lock ("" free); not kept across a restart
  // The graph SPARQL queries read (ontology, scene_extra_, scene_imports_, elements); the
  // engine asks for it again only when store_.version() has changed since: so whatever
  // changes that graph must change the version (apply and change_scene do).
  std::vector<Triple> sparql_graph() const;
  SparqlEngine sparql_;
  long rejected_ = 0;
  long commits_ = 0;
};

}  // namespace skillbus::wm
