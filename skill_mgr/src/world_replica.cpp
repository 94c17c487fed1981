#include "world_replica.hpp"

#include <fstream>
#include <map>
#include <set>
#include <stdexcept>
#include <iterator>

#include "skillbus/wm/convert.hpp"
#include "skillbus/wm/ontology_files.hpp"
#include "skillbus_msgs/wm_change_t.hpp"
#include "skillbus_msgs/wm_elements_t.hpp"
#include "skillbus_msgs/wm_query_t.hpp"
#include "skillbus_msgs/wm_scene_t.hpp"

namespace skillbus::skills {

using namespace skillbus_msgs;

WorldReplica::WorldReplica(Bus& bus, LockstepParticipant& participant, const std::vector<std::string>& ontology_files,
                           bool wall_clock)
    : bus_(bus), client_(bus, "WM", "skill_mgr"), store_(ontology_), wall_clock_(wall_clock) {
  ontology_from_server_ = ontology_files.empty();
  if (!ontology_from_server_) wm::load_ontology_files(ontology_, prefixes_, ontology_files);
  participant.subscribe(channel("SB_WM_CHANGES"), [this](const StampedMessage& m) { on_change(m); });
}

namespace {

constexpr int32_t kPage = 200;  // elements a snapshot reply: small messages survive UDP

// A change applied to plain containers so that applying it twice changes nothing more
// (pages read at later versions may already hold it).
void replay(const wm_change_t& ch, std::map<std::string, wm::Element>& elements, std::set<wm::Relation>& relations) {
  for (const auto& m : ch.ops) {
    const wm::Op op = wm::from_msg(m);
    switch (op.kind) {
      case wm::Op::AddElement:
      case wm::Op::UpdateElement: elements[op.element.id] = op.element; break;
      case wm::Op::RemoveElement:
        elements.erase(op.element.id);
        for (auto it = relations.begin(); it != relations.end();)
          it = (it->subject == op.element.id || it->object == op.element.id) ? relations.erase(it) : std::next(it);
        break;
      case wm::Op::AddRelation: relations.insert(op.relation); break;
      case wm::Op::RemoveRelation: relations.erase(op.relation); break;
      case wm::Op::ExpectElement: break;  // a check the server made: it changes nothing
    }
  }
}

}  // namespace

bool WorldReplica::ensure(std::chrono::milliseconds timeout, std::string* why) {
  if (ready_ && !stale_) return true;
  // Pages by id (stable while others write) and the changes made meanwhile (first page's
  // version on), replayed over them: a busy world still gives a replica at once.
  try {
    CallOptions opts;
    opts.timeout = timeout;
    if (ontology_from_server_) {  // (a scene load may have brought classes: read it with the world)
      const auto rep = client_.call<wm_scene_t>("ontology", wm_scene_t{}, opts);
      wm::Prefixes px;
      wm::Ontology fresh;
      fresh.add_triples(wm::parse_turtle(rep.turtle, px, "the world model's ontology"), px);
      ontology_ = std::move(fresh);  // (in place: store_ judges by this object)
      prefixes_ = px;
    }
    for (int attempt = 0; attempt < 5; ++attempt) {
      collecting_ = true;
      collected_.clear();
      std::map<std::string, wm::Element> elements;
      std::set<wm::Relation> relations;
      int64_t first = -1, last = -1;
      std::string after;
      for (;;) {
        wm_query_t q{};
        q.after = after;
        q.limit = kPage;
        const auto page = client_.call<wm_elements_t>("snapshot", q, opts);
        if (first < 0) first = page.version;
        last = page.version;
        for (const auto& e : page.elements) elements[e.id] = wm::from_msg(e);
        for (const auto& r : page.relations) relations.insert(wm::from_msg(r));
        if (page.num_elements < kPage) break;
        // Pages must advance by id, or a server that ignores `after` is asked for the same
        // page for ever.
        if (page.elements.empty() || !(page.elements.back().id > after))
          throw std::runtime_error("the snapshot's page after '" + after + "' did not end past it: the world model "
                                   "server does not page by id");
        after = page.elements.back().id;
      }
      auto have = [&] {
        std::set<int64_t> v;
        for (const auto& c : collected_)
          if (c.version > first && c.version <= last) v.insert(c.version);
        return static_cast<int64_t>(v.size());
      };
      const auto deadline = std::chrono::steady_clock::now() + std::chrono::seconds(2);
      while (wall_clock_ && have() < last - first && std::chrono::steady_clock::now() < deadline)
        bus_.handle(std::chrono::milliseconds(10));  // the changes still in flight
      collecting_ = false;
      if (have() < last - first) continue;  // a change of that span never came: read again
      std::sort(collected_.begin(), collected_.end(),
                [](const wm_change_t& a, const wm_change_t& b) { return a.version < b.version; });
      int64_t version = first;
      bool reset = false;
      for (const auto& c : collected_) {
        if (c.version != version + 1) continue;  // older, or a duplicate
        if (c.reset) reset = true;
        replay(c, elements, relations);
        version = c.version;
      }
      if (reset) continue;  // a scene was loaded meanwhile: read it whole
      std::vector<wm::Element> el;
      for (auto& [id, e] : elements) el.push_back(std::move(e));
      store_.reset(std::move(el), {relations.begin(), relations.end()}, version, 1);
      ready_ = true;
      stale_ = false;
      return true;
    }
    if (why) *why = "no world model: the world kept changing and the changes meanwhile did not all arrive";
    return false;
  } catch (const std::exception& e) {
    collecting_ = false;
    if (why) *why = std::string("no world model: ") + e.what();
    return false;
  }
}

void WorldReplica::on_change(const StampedMessage& m) {
  wm_change_t ch;
  if (!decode_msg(m.data.data(), m.data.size(), ch)) return;
  if (collecting_) {  // a resync is reading pages: these changes are replayed over them
    collected_.push_back(std::move(ch));
    return;
  }
  if (!ready_) return;
  if (ch.version <= store_.version()) return;
  if (ch.reset || ch.version != store_.version() + 1) {
    stale_ = true;  // resync on the next ensure(), outside this handler
    return;
  }
  std::vector<wm::Op> ops;
  try {
    for (const auto& o : ch.ops) ops.push_back(wm::from_msg(o));
    if (!ops.empty()) store_.apply(ops);
  } catch (const std::exception&) {
    stale_ = true;
  }
}

void WorldReplica::wait_for(int64_t version, std::chrono::milliseconds timeout) {
  if (!wall_clock_) return;
  const auto deadline = std::chrono::steady_clock::now() + timeout;
  while (ready_ && !stale_ && store_.version() < version && std::chrono::steady_clock::now() < deadline)
    bus_.handle(std::chrono::milliseconds(10));
  if (store_.version() < version) stale_ = true;
}

}  // namespace skillbus::skills
