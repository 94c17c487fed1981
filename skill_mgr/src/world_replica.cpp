#include "world_replica.hpp"

#include <fstream>
#include <iterator>

#include "skillbus/wm/convert.hpp"
#include "skillbus_msgs/wm_change_t.hpp"
#include "skillbus_msgs/wm_elements_t.hpp"
#include "skillbus_msgs/wm_query_t.hpp"

namespace skillbus::skills {

using namespace skillbus_msgs;

WorldReplica::WorldReplica(Bus& bus, LockstepParticipant& participant, const std::vector<std::string>& ontology_files,
                           bool wall_clock)
    : bus_(bus), client_(bus, "WM", "skill_mgr"), store_(ontology_), wall_clock_(wall_clock) {
  for (const auto& f : ontology_files) {
    std::ifstream in(f);
    if (!in) throw std::runtime_error("cannot read ontology " + f);
    ontology_.load_turtle(std::string((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>()),
                          prefixes_, f);
  }
  participant.subscribe(channel("SB_WM_CHANGES"), [this](const StampedMessage& m) { on_change(m); });
}

bool WorldReplica::ensure(std::chrono::milliseconds timeout, std::string* why) {
  if (ready_ && !stale_) return true;
  try {
    CallOptions opts;
    opts.timeout = timeout;
    std::vector<wm::Element> elements;
    std::vector<wm::Relation> relations;
    int64_t version = -1;
    for (int attempt = 0; attempt < 10; ++attempt) {
      elements.clear();
      relations.clear();
      version = -1;
      int32_t offset = 0;
      bool consistent = true;
      for (;;) {
        wm_query_t q{};
        q.offset = offset;
        q.limit = 200;
        const auto page = client_.call<wm_elements_t>("snapshot", q, opts);
        if (version < 0) version = page.version;
        if (page.version != version) {
          consistent = false;
          break;
        }
        for (const auto& e : page.elements) elements.push_back(wm::from_msg(e));
        for (const auto& r : page.relations) relations.push_back(wm::from_msg(r));
        offset += page.num_elements;
        if (page.num_elements == 0 || offset >= page.total) break;
      }
      if (consistent) break;
    }
    std::sort(relations.begin(), relations.end());
    relations.erase(std::unique(relations.begin(), relations.end()), relations.end());
    store_.reset(std::move(elements), std::move(relations), version, 1);
    ready_ = true;
    stale_ = false;
    return true;
  } catch (const std::exception& e) {
    if (why) *why = std::string("no world model: ") + e.what();
    return false;
  }
}

void WorldReplica::on_change(const StampedMessage& m) {
  wm_change_t ch;
  if (!decode_msg(m.data.data(), m.data.size(), ch) || !ready_) return;
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
