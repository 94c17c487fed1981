#include "skillbus/wm/server.hpp"

#include <fcntl.h>
#include <sys/stat.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <chrono>
#include <cstdlib>
#include <cstring>
#include <fstream>
#include <iterator>

#include "skillbus/digest.hpp"
#include "skillbus/files.hpp"
#include "skillbus/wm/convert.hpp"
#include "skillbus/wm/ontology_files.hpp"
#include "skillbus/wm/scene.hpp"
#include "skillbus/wm/sparql.hpp"
#include "skillbus/wm/transforms.hpp"
#include "skillbus_msgs/wm_value_t.hpp"

namespace skillbus::wm {

using namespace skillbus_msgs;

namespace {

const char* kLog = "wm_server";

std::string read_file(const std::string& path) {
  std::ifstream f(path, std::ios::binary);
  if (!f) throw WmError("cannot read " + path);
  return std::string((std::istreambuf_iterator<char>(f)), std::istreambuf_iterator<char>());
}

ParticipantConfig participant_config(const ServerOptions& o) {
  ParticipantConfig c;
  c.name = o.name;
  c.kind = "wm_server";
  c.mode = o.wall_clock ? ClockMode::WallClock : ClockMode::Lockstep;
  c.wall_frame_period_ns = o.frame_period_ns;
  return c;
}

std::string txn_key(const std::string& client, int64_t request) { return client + "\n" + std::to_string(request); }

// What a transaction asks for: its operations, by their encoding.
Digest ops_digest(const wm_txn_t& txn) {
  Sha256 h;
  for (const auto& o : txn.ops) {
    std::vector<uint8_t> buf(static_cast<size_t>(o.getEncodedSize()));
    o.encode(buf.data(), 0, static_cast<int>(buf.size()));
    h.update(buf.data(), buf.size());
  }
  return h.finish();
}

void set_digest(wm_commit_t& c, const Digest& d) { std::copy(d.begin(), d.end(), c.request_digest); }

bool known_digest(const wm_commit_t& c) {
  return std::any_of(std::begin(c.request_digest), std::end(c.request_digest), [](uint8_t b) { return b != 0; });
}

}  // namespace

WorldModelServer::WorldModelServer(Bus& bus, ServerOptions options)
    : bus_(bus),
      opt_(std::move(options)),
      store_(ontology_),
      journal_(opt_.data_dir),
      participant_(bus, participant_config(opt_)),
      rpc_(bus, "WM", 4096, opt_.rpc_memory_bytes) {
  library_ = OntologyLibrary(opt_.ontology_library);
  OntologyLoad loaded = load_ontology_files(ontology_, prefixes_, opt_.ontology_files);
  ontology_triples_ = std::move(loaded.triples);
  OntologyLoad imported = library_.resolve(ontology_, prefixes_);
  ontology_triples_.insert(ontology_triples_.end(), imported.triples.begin(), imported.triples.end());
  ontology_report_ = std::to_string(loaded.files.size() + imported.files.size()) + " ontology file(s), " +
                     std::to_string(ontology_.class_count()) + " concepts";
  for (const auto& i : imported.missing_imports)
    SB_WARN(kLog, "the ontology imports " << i << ", which neither an --ontology file nor the --ontology-library "
                                          "declares (give its file or folder)");
  base_ontology_ = ontology_;  // what every scene load starts from
  recover();

  rpc_.add_method<wm_query_t, wm_elements_t>("get", [this](const wm_query_t& q) { return on_get(q); });
  add_ontology_methods();
  rpc_.add_method<wm_query_t, wm_elements_t>("query", [this](const wm_query_t& q) {
    return on_query(q, "query", Relations::Touching);
  });
  // Pages keep each reply small: one lost UDP fragment loses a whole LCM message, and a
  // multi-megabyte reply overruns a default socket buffer. A snapshot page is a query
  // for everything.
  rpc_.add_method<wm_query_t, wm_elements_t>("snapshot", [this](const wm_query_t& q) {
    wm_query_t all{};
    all.after = q.after;
    all.offset = q.offset;
    all.limit = q.limit;
    return on_query(all, "snapshot", Relations::ByObject);
  });
  // A client whose request ids must not repeat across its restarts (a lockstep
  // participant names its transactions by its name and a counter, the same every run)
  // asks where its counter stands before it writes: the highest request id the server
  // has answered for it (0: none), so a restarted client never gets an old answer.
  rpc_.add_method<wm_commit_t, wm_commit_t>("last_request", [this](const wm_commit_t& q) {
    wm_commit_t out{};
    out.client_id = q.client_id;
    auto it = last_request_.find(q.client_id);
    out.request_id = it == last_request_.end() ? 0 : it->second;
    out.version = store_.version();
    return out;
  });
  rpc_.add_method<wm_txn_t, wm_commit_t>("commit", [this](const wm_txn_t& t) {
    wm_commit_t c = commit(t);
    if (!c.error.empty()) throw WmError(c.error);
    return c;
  });
  rpc_.add_method<wm_scene_t, wm_scene_t>("load_scene", [this](const wm_scene_t& r) { return on_load_scene(r); });
  rpc_.add_method<wm_scene_t, wm_scene_t>("save_scene", [this](const wm_scene_t& r) { return on_save_scene(r); });
  rpc_.add_method<wm_transform_t, wm_transform_t>("transform", [this](const wm_transform_t& r) { return on_transform(r); });
  rpc_.add_method<wm_relation_t, wm_value_t>("may_relate", [this](const wm_relation_t& r) {
    for (const auto* c : {&r.subject, &r.object})
      if (!ontology_.is_class(*c)) throw WmError("unknown concept '" + *c + "'");
    if (!ontology_.is_relation(r.predicate)) throw WmError("unknown relation type '" + r.predicate + "'");
    wm_value_t v{};
    v.type = wm_value_t::BOOL;
    v.b = ontology_.may_relate(r.subject, r.predicate, r.object);
    return v;
  });

  participant_.subscribe(channel("SB_WM_TXN"), [this](const StampedMessage& m) { on_txn_message(m); });
  participant_.on_frame = [this](int64_t f, int64_t t) { on_frame(f, t); };
}

void WorldModelServer::recover() {
  Journal::Recovered rec = journal_.recover();
  // The ontologies the loaded scene imported, then its own axioms (the generation that goes
  // with the snapshot), before the world and the journal's records, which may use their classes.
  const Journal::SceneFiles files = journal_.settle_scene_files(rec.snapshot ? rec.snapshot->version() : 0);
  if (!files.imports.empty()) {
    scene_imports_ = parse_turtle(files.imports, prefixes_, files.imports_path);
    ontology_.add_triples(scene_imports_, prefixes_);
  }
  if (!files.extra.empty()) {
    scene_extra_ = parse_turtle(files.extra, prefixes_, files.extra_path);
    ontology_.add_triples(scene_extra_, prefixes_);
  }
  std::string report;
  if (rec.snapshot) {
    // Element by element from the mapped file into the store: a large world is never
    // held a second time as messages.
    const SnapshotFile& snap = *rec.snapshot;
    store_.clear();
    snap.for_each_element([this](wm_element_t& m) { store_.insert_element(from_msg(m)); });
    snap.for_each_relation([this](wm_relation_t& m) { store_.insert_relation(from_msg(m)); });
    store_.set_version(snap.version(), snap.next_id());
    for (const auto& c : snap.recent()) remember(c);
    rec.snapshot.reset();  // unmaps the file
    report += "snapshot at version " + std::to_string(store_.version());
  } else if (!opt_.scene_file.empty() && rec.txns.empty()) {
    load_scene_text(read_file(opt_.scene_file), opt_.scene_file, &report);
    report = "new data directory; loaded scene " + opt_.scene_file + (report.empty() ? "" : " (" + report + ")");
  }
  long replayed = 0;
  for (const auto& txn : rec.txns) {
    if (txn.expected_version < store_.version()) continue;  // already in the snapshot
    std::vector<Op> ops;
    for (const auto& o : txn.ops) ops.push_back(from_msg(o));
    const TxnResult r = store_.apply(ops, txn.expected_version);  // a failure here is a corrupt journal
    wm_commit_t c{};
    c.client_id = txn.client_id;
    c.request_id = txn.request_id;
    set_digest(c, ops_digest(txn));
    c.version = r.version;
    c.ids = r.ids;
    c.num_ids = static_cast<int32_t>(c.ids.size());
    if (!txn.client_id.empty()) remember(c);
    ++replayed;
  }
  if (replayed) report += (report.empty() ? "" : "; ") + std::string("replayed ") + std::to_string(replayed) + " journal records";
  if (!rec.note.empty()) report += "; " + rec.note;
  startup_report_ = "version " + std::to_string(store_.version()) + ", " + std::to_string(store_.elements().size()) +
                    " elements" + (report.empty() ? "" : " (" + report + ")") + "; " + ontology_report_;
}

void WorldModelServer::remember(const wm_commit_t& c) {
  int64_t& last = last_request_[c.client_id];
  last = std::max(last, c.request_id);
  const std::string key = txn_key(c.client_id, c.request_id);
  if (recent_.emplace(key, c).second) recent_order_.push_back(key);
  while (recent_order_.size() > opt_.recent_memory) {
    recent_.erase(recent_order_.front());
    recent_order_.pop_front();
  }
}

void WorldModelServer::snapshot(bool in_background) {
  // An image of the world is pointers to its immutable elements: a few milliseconds for
  // 100,000 of them; the encoding and the writing happen in the journal's thread.
  const auto t0 = std::chrono::steady_clock::now();
  SnapshotData s;
  s.world = store_.image();
  s.recent.reserve(recent_order_.size());
  for (const auto& key : recent_order_) s.recent.push_back(recent_.at(key));
  const double ms = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
  if (!in_background) {
    journal_.write_snapshot(s);
    return;
  }
  const int64_t version = s.world.version;
  if (journal_.start_snapshot(std::move(s)))
    SB_INFO(kLog, "writing a snapshot at version " << version << " in the background (its image took " << ms
                                                   << " ms)");
}

wm_commit_t WorldModelServer::commit(wm_txn_t txn) {
  const Digest asked = ops_digest(txn);
  if (!txn.client_id.empty()) {
    auto it = recent_.find(txn_key(txn.client_id, txn.request_id));
    if (it != recent_.end()) {
      const wm_commit_t& was = it->second;
      if (!known_digest(was) || std::equal(asked.begin(), asked.end(), was.request_digest))
        return was;  // a retry of a committed transaction: once only
      ++rejected_;  // the id was used before for other operations: never answer it with that result
      wm_commit_t refused{};
      refused.client_id = txn.client_id;
      refused.request_id = txn.request_id;
      refused.version = store_.version();
      refused.error = "not applied: request " + std::to_string(txn.request_id) + " of " + txn.client_id +
                      " was answered before for other operations (a client that reuses its request ids, e.g. "
                      "after a restart, must go on from wm.last_request)";
      set_digest(refused, asked);
      return refused;
    }
  }
  wm_commit_t c{};
  c.client_id = txn.client_id;
  c.request_id = txn.request_id;
  set_digest(c, asked);
  TxnResult r;
  try {
    std::vector<Op> ops;
    for (const auto& o : txn.ops) ops.push_back(from_msg(o));
    r = store_.apply(ops, txn.expected_version);
    txn.expected_version = r.version - 1;  // the journal records the version it applied to
    try {
      journal_.append(txn);
    } catch (const WmError& e) {
      store_.undo_last();
      throw WmError(std::string("not committed, it could not be made durable: ") + e.what());
    }
  } catch (const WmError& e) {
    ++rejected_;
    c.version = store_.version();
    c.error = e.what();
    return c;
  }
  if (++commits_ == opt_.crash_after_commits) {
    SB_ERROR(kLog, "crashing on purpose after " << commits_ << " commits (--crash-after-commits)");
    std::_Exit(137);  // durable but not acknowledged: the retry after a restart must not apply it again
  }
  c.version = r.version;
  c.ids = r.ids;
  c.num_ids = static_cast<int32_t>(c.ids.size());
  if (!txn.client_id.empty()) remember(c);
  wm_change_t change{};
  change.version = r.version;
  for (const auto& op : r.effect) change.ops.push_back(to_msg(op));
  change.num_ops = static_cast<int32_t>(change.ops.size());
  if (opt_.wall_clock) {
    publish_change_now(std::move(change));
  } else {
    pending_changes_.push_back(std::move(change));
  }
  if (journal_.snapshot_due(opt_.snapshot_every)) snapshot(true);
  return c;
}

void WorldModelServer::on_txn_message(const StampedMessage& m) {
  wm_txn_t txn;
  if (!decode_msg(m.data.data(), m.data.size(), txn))
    throw WmError("SB_WM_TXN from " + m.stamp.sender + " in frame " + std::to_string(m.stamp.frame) +
                  " is not a wm_txn_t");
  wm_commit_t c = commit(txn);
  pending_results_.push_back(std::move(c));
}

void WorldModelServer::publish_change_now(wm_change_t change) {
  if (opt_.hold_changes_ns > 0) {  // (tests: on_frame publishes it when its time has come)
    held_changes_.emplace_back(std::chrono::steady_clock::now() + std::chrono::nanoseconds(opt_.hold_changes_ns),
                               std::move(change));
    return;
  }
  pending_changes_.push_back(std::move(change));
  on_frame(participant_.frame(), 0);
}

void WorldModelServer::on_frame(int64_t, int64_t) {
  // Changes and lockstep results go out inside a frame so that they are stamped,
  // counted and delivered in canonical order (RPC commits between frames wait here).
  while (!held_changes_.empty() && held_changes_.front().first <= std::chrono::steady_clock::now()) {
    pending_changes_.push_back(std::move(held_changes_.front().second));
    held_changes_.pop_front();
  }
  for (auto& c : pending_results_) participant_.publish(channel("SB_WM_TXN_RESULT"), c);
  for (auto& ch : pending_changes_) participant_.publish(channel("SB_WM_CHANGES"), ch);
  pending_results_.clear();
  pending_changes_.clear();
}

wm_elements_t WorldModelServer::elements_reply(const std::vector<const Element*>& found, bool ids_only,
                                               const char* method, Relations relations) const {
  wm_elements_t out{};
  out.version = store_.version();
  out.next_id = store_.next_id();
  out.total = static_cast<int64_t>(store_.elements().size());
  // A reply is bounded, counted as it is built (a reply of every element of a large
  // world is never built to be refused): a larger one would be lost to a dropped UDP
  // fragment, or overrun the receiver's socket buffer, and never arrive.
  size_t bytes = 64;
  for (const Element* e : found) {
    out.elements.push_back(ids_only ? to_msg(Element{e->id, e->type, e->label, {}}) : to_msg(*e));
    bytes += static_cast<size_t>(out.elements.back()._getEncodedSizeNoHash());
    if (bytes > opt_.max_reply_bytes) too_large(method, out.elements.size(), found.size());
  }
  out.num_elements = static_cast<int32_t>(out.elements.size());
  if (ids_only) return out;
  const auto rels = relations == Relations::Touching ? store_.relations_touching(found) : store_.relations_to(found);
  for (const auto& r : rels) {
    out.relations.push_back(to_msg(r));
    bytes += static_cast<size_t>(out.relations.back()._getEncodedSizeNoHash());
    if (bytes > opt_.max_reply_bytes) too_large(method, found.size(), found.size());
  }
  out.num_relations = static_cast<int32_t>(out.relations.size());
  return out;
}

void WorldModelServer::too_large(const char* method, size_t fitted, size_t found) const {
  throw WmError(std::string(method) + ": the reply of " + std::to_string(found) + " elements would be larger than " +
                std::to_string(opt_.max_reply_bytes) + " bytes, the most a reply carries (" + std::to_string(fitted) +
                " fit); ask for it in pages: wm_query_t.limit (elements a page) and .after (the last id of the "
                "previous page), or ids_only; skillbus.world.client.query_all and WorldModelInterface page by "
                "themselves");
}

wm_elements_t WorldModelServer::on_get(const wm_query_t& q) const {
  std::vector<const Element*> found;
  for (const auto& id : q.ids) {
    const Element* e = store_.get(id);
    if (!e) throw WmError("unknown element id '" + id + "'");
    found.push_back(e);
  }
  return elements_reply(found, false, "get", Relations::Touching);
}

wm_elements_t WorldModelServer::on_query(const wm_query_t& m, const char* method, Relations relations) const {
  if (m.offset < 0 || m.limit < 0) throw WmError(std::string(method) + ": offset and limit must not be negative");
  Query q;
  q.ids = m.ids;
  q.type = m.type;
  q.exact_type = m.exact_type;
  q.label = m.label;
  if (!q.type.empty() && !ontology_.is_class(q.type)) throw WmError("unknown type '" + q.type + "' in query");
  q.properties = properties_from_msg(m.properties, "the query");
  for (const auto& r : m.relations) {
    // (a misspelt relation type matched nothing: an empty answer, where a commit refuses it)
    if (!r.predicate.empty() && r.predicate != "*" && !ontology_.is_relation(r.predicate))
      throw WmError("unknown relation type '" + r.predicate + "' in query");
    q.relations.push_back(from_msg(r));
  }
  Page page;
  page.after = m.after;
  page.offset = m.offset;
  page.limit = m.limit;
  return elements_reply(store_.query(q, page), m.ids_only, method, relations);
}

std::vector<Triple> WorldModelServer::sparql_graph() const {
  std::vector<Triple> all = all_axioms();
  std::vector<Triple> scene = scene_triples(store_, prefixes_);
  all.insert(all.end(), std::make_move_iterator(scene.begin()), std::make_move_iterator(scene.end()));
  return all;
}

bool WorldModelServer::snapshot_on_disk(int64_t version) const {
  try {
    return SnapshotFile(opt_.data_dir + "/snapshot.bin").version() == version;
  } catch (const std::exception&) {
    return false;
  }
}

void WorldModelServer::load_scene_text(const std::string& text, const std::string& source, std::string* report) {
  // From the --ontology files (and what they import), not from the live ontology: a scene
  // replaces the last one's imports and axioms, and what it imports is found again even if
  // the last scene had imported it too. The live ontology changes only if the whole scene loads.
  Ontology onto = base_ontology_;
  Prefixes px = prefixes_;
  Scene scene = read_scene(text, onto, px, source);
  const OntologyLoad imported = library_.resolve(onto, px);  // the scene's owl:imports, from the library
  // Again, now that the imported classes are known: an axiom of the scene between them
  // (a subclass of an imported class) is read as a restart reads it (files, imports, scene).
  onto.add_triples(scene.extra, px);
  check_scene_types(scene, onto, source);
  WorldStore check(onto);
  std::vector<Op> ops;
  for (const auto& e : scene.elements) ops.push_back(Op{Op::AddElement, e, {}});
  for (const auto& r : scene.relations) ops.push_back(Op{Op::AddRelation, {}, r});
  if (!ops.empty()) check.apply(ops);  // validates every element and relation
  SceneChange change;
  change.what = "the scene";
  change.ontology = std::move(onto);
  change.prefixes = std::move(px);
  change.imports = imported.triples;
  change.extra = std::move(scene.extra);
  change.new_world = true;
  change.elements = std::move(scene.elements);
  change.relations = std::move(scene.relations);
  change_scene(std::move(change));
  for (const auto& f : imported.files) scene.notes.push_back("imported the ontology " + f);
  for (const auto& i : imported.missing_imports)
    scene.notes.push_back("imports " + i + ", which neither the server's ontology nor its library declares");
  for (const auto& n : scene.notes) *report += (report->empty() ? "" : "; ") + n;
}

// What the change replaces is kept to put back if it cannot be made durable (a full disk):
// else the world would go on at a version no journal record explains, every later commit
// would be acknowledged into a journal that a restart refuses, and the scene files in
// force would describe a scene the snapshot does not hold.
void WorldModelServer::change_scene(SceneChange c) {
  const int64_t version = store_.version() + 1;
  const std::string imports_ttl = c.imports.empty() ? "" : write_turtle(c.imports, c.prefixes);
  const std::string extra_ttl = c.extra.empty() ? "" : write_turtle(c.extra, c.prefixes);
  const WorldImage was_world = store_.image();
  Ontology was_ontology = ontology_;
  Prefixes was_prefixes = prefixes_;
  std::vector<Triple> was_scene_extra = scene_extra_, was_scene_imports = scene_imports_;
  try {
    journal_.write_scene_files(version, imports_ttl, extra_ttl);
    ontology_ = std::move(c.ontology);
    prefixes_ = std::move(c.prefixes);
    scene_extra_ = std::move(c.extra);
    scene_imports_ = std::move(c.imports);
    if (c.new_world)
      store_.reset(std::move(c.elements), std::move(c.relations), version, 1);
    else
      store_.set_version(version, store_.next_id());
    snapshot(false);  // durable as a snapshot before the reply
  } catch (const WmError& e) {
    if (snapshot_on_disk(version)) {
      // The snapshot is in place and only the journal's switch failed: the disk holds the
      // change, and so does the server; no commit until a restart.
      journal_.fail(std::string("the journal could not be restarted after a change of ") + c.what + " (" +
                    e.what() + "); restart the server");
      throw WmError(c.what + " changed and is on disk as a snapshot, but the journal could not be restarted (" +
                    e.what() + "): no commit is taken until the server restarts");
    }
    std::vector<Element> elements;
    std::vector<Relation> relations;
    for (const auto& el : was_world.elements) elements.push_back(*el);
    for (const auto& r : was_world.relations) relations.push_back(*r);
    ontology_ = std::move(was_ontology);
    prefixes_ = std::move(was_prefixes);
    scene_extra_ = std::move(was_scene_extra);
    scene_imports_ = std::move(was_scene_imports);
    store_.reset(std::move(elements), std::move(relations), was_world.version, was_world.next_id);
    try {
      journal_.remove_scene_files(version);
    } catch (const WmError& again) {
      // Left in place they would be taken for the scene of a later snapshot at this version.
      journal_.fail("a change of " + c.what + " failed (" + e.what() + ") and its scene files could not be removed (" +
                    again.what() + "); restart the server");
    }
    throw WmError(c.what + " could not be made durable, nothing changed: " + e.what());
  }
  try {
    journal_.settle_scene_files(version);  // the generations it replaced
  } catch (const WmError& e) {
    SB_WARN(kLog, "the scene files of earlier versions stay in " << journal_.dir() << " until the next start: "
                                                                   << e.what());
  }
}

// Scene files named in a request live in DATA/scenes: a request names a scene, never a
// path (skillbus/files.hpp), so it can neither overwrite the journal nor read other files.
std::string WorldModelServer::scene_path(const std::string& name) const {
  try {
    return file_in(opt_.data_dir.empty() ? "" : opt_.data_dir + "/scenes", name, ".ttl", "scene name");
  } catch (const std::invalid_argument& e) {
    throw WmError(e.what());
  }
}

wm_scene_t WorldModelServer::on_load_scene(const wm_scene_t& req) {
  const std::string source = req.path.empty() ? "the request" : "scene " + req.path;
  const std::string text = req.path.empty() ? req.turtle : read_file(scene_path(req.path));
  wm_scene_t out{};
  load_scene_text(text, source, &out.report);
  out.version = store_.version();
  announce_reset();  // replicas resync on a scene load: it replaces everything
  return out;
}

wm_scene_t WorldModelServer::on_save_scene(const wm_scene_t& req) const {
  wm_scene_t out{};
  out.turtle = write_scene(store_, prefixes_, scene_extra_);
  out.version = store_.version();
  if (!req.path.empty()) {
    const std::string path = scene_path(req.path);
    const std::string dir = path.substr(0, path.rfind('/'));
    ::mkdir(dir.c_str(), 0700);
    // Beside, synced, then renamed over the old file: a failed or cut write (a full disk,
    // a crash) leaves the previous scene whole, and the reply means the file is on disk.
    try {
      write_file_durably(dir, path.substr(path.rfind('/') + 1), out.turtle);
    } catch (const WmError& e) {
      throw WmError("cannot write the scene " + req.path + ": " + e.what());
    }
    out.path = req.path;
  }
  return out;
}

wm_transform_t WorldModelServer::on_transform(const wm_transform_t& req) const {
  const Eigen::Isometry3d t = transform(store_, req.source, req.target);
  wm_transform_t out = req;
  const Eigen::Quaterniond q(t.rotation());
  for (int i = 0; i < 3; ++i) out.translation[i] = t.translation()[i];
  out.rotation[0] = q.x();
  out.rotation[1] = q.y();
  out.rotation[2] = q.z();
  out.rotation[3] = q.w();
  return out;
}

RunResult WorldModelServer::run_until(std::function<bool()> should_stop) {
  SB_INFO(kLog, "serving " << rpc_request_channel("WM") << " on " << bus_.url() << ": " << startup_report_);
  participant_.on_frame = [this](int64_t f, int64_t t) { on_frame(f, t); };
  participant_.interrupted = should_stop;  // (also while it waits for a clock: LockstepParticipant)
  return participant_.run();
}

}  // namespace skillbus::wm
