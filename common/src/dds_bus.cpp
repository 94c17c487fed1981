#include "dds_bus.hpp"

#include <algorithm>
#include <cstdlib>
#include <regex>

#include "channel_names.hpp"
#include "envelope.h"
#include "skillbus/log.hpp"

namespace skillbus {

namespace {

using detail::ends_with;

// A state reader keeps this many samples it has not taken (like LCM's 4 MB receive buffer,
// so a burst, a flood of forgeries included, does not push a frame's state out before it
// is read); keep-last, so a slow reader never holds its writer back.
constexpr int kStateDepth = 1024;
constexpr int kMaxParticipants = 120;  // per host and domain (Cyclone's participant index)
// How long a process that vanished without saying so (killed) is still matched: a reliable
// writer keeps what it sent for that process's readers until then, and blocks once too
// much is unacknowledged. Cyclone's default is 10 s. (As skillbus.dds.LEASE_S.)
constexpr int kLeaseSeconds = 3;
constexpr int kLateJoinerDepth = 16;   // samples a writer keeps for readers that match it later
constexpr dds_duration_t kLateJoinerWindow = DDS_SECS(2);  // of those, only what was written this long before the reader

// An RPC request written before a server's reader existed is never delivered to it: a
// restarted server must not execute its predecessor's requests (the client's retry
// reaches it), as on LCM.
bool is_request(const std::string& channel) { return ends_with(channel, "_REQ"); }

// State: what a publisher sends again and again, each message replacing the last (the
// physics' arm and simulator state, the objects a camera sees, articulated joints).
bool is_state(const std::string& channel) {
  return ends_with(channel, "_STATE") || ends_with(channel, "_OBJECTS") || ends_with(channel, "_ARTICULATION");
}

// How long before a reader existed a sample may have been written and still be delivered
// to it. RPC requests: none (above). State: none either, as on LCM: a reader that comes
// later wants the state as it is, and a writer's history for late joiners held a second
// of it under lockstep (a probe reading the arm's pose saw where it had been before its
// last move). What was written after the reader existed still arrives when discovery
// matches them late.
dds_duration_t late_joiner_window(const std::string& channel) {
  return is_request(channel) || is_state(channel) ? 0 : kLateJoinerWindow;
}

std::string dds_error(dds_return_t r) { return dds_strretcode(r); }
}  // namespace

DdsUrl parse_dds_url(const std::string& url) {
  static const std::regex form(R"(^dds://(\d+)(?:\?(.*))?$)");
  std::smatch m;
  if (!std::regex_match(url, m, form))
    throw BusError("bus URL '" + url +
                   "': expected dds://DOMAIN (a number 0-232), optionally ?peers=HOST,...&interface=ADDRESS&state=best-effort");
  DdsUrl u;
  if (m[1].str().size() > 3 || std::stoi(m[1].str()) > 232)
    throw BusError("bus URL '" + url + "': DDS domain " + m[1].str() + " is out of range (0-232)");
  u.domain = std::stoi(m[1].str());
  std::string query = m[2].str();
  size_t start = 0;
  while (start <= query.size() && !query.empty()) {
    const size_t end = std::min(query.find('&', start), query.size());
    const std::string part = query.substr(start, end - start);
    start = end + 1;
    if (part.empty()) continue;
    const size_t eq = part.find('=');
    const std::string key = part.substr(0, eq), value = eq == std::string::npos ? "" : part.substr(eq + 1);
    if (key == "peers") {
      size_t s = 0;
      while (s <= value.size()) {
        const size_t e = std::min(value.find(',', s), value.size());
        if (e > s) u.peers.push_back(value.substr(s, e - s));
        s = e + 1;
      }
    } else if (key == "interface" && !value.empty()) {
      u.interface = value;
    } else if (key == "state" && (value == "best-effort" || value == "reliable")) {
      u.state_best_effort = value == "best-effort";
    } else {
      throw BusError("bus URL '" + url + "': unknown option '" + part + "' (peers=, interface=, state=best-effort)");
    }
    if (end == query.size()) break;
  }
  return u;
}

std::string dds_config_xml(const DdsUrl& u) {
  std::string peers = "<Peer address=\"localhost\"/>";
  for (const auto& p : u.peers) peers += "<Peer address=\"" + p + "\"/>";
  return "<CycloneDDS><Domain id=\"any\"><General><Interfaces><NetworkInterface address=\"" + u.interface +
         "\" multicast=\"false\"/></Interfaces><AllowMulticast>false</AllowMulticast></General>"
         "<Discovery><ParticipantIndex>auto</ParticipantIndex><MaxAutoParticipantIndex>" +
         std::to_string(kMaxParticipants) + "</MaxAutoParticipantIndex><LeaseDuration>" +
         std::to_string(kLeaseSeconds) + " s</LeaseDuration><Peers>" + peers +
         "</Peers></Discovery></Domain></CycloneDDS>";
}

void check_dds_local(const DdsUrl& u, const std::string& url) {
  const char* allowed = std::getenv("SKILLBUS_NETWORK");
  if (allowed && *allowed) return;
  std::vector<std::string> all{u.interface};
  all.insert(all.end(), u.peers.begin(), u.peers.end());
  std::string outside;
  for (const auto& a : all)
    if (a.rfind("127.", 0) != 0 && a != "localhost") outside += (outside.empty() ? "" : ", ") + a;
  if (!outside.empty())
    throw BusError("bus URL '" + url + "': " + outside +
                   " would let other hosts reach this robot's bus. skillbus stays on this host unless told otherwise: "
                   "allow the network with --network IFACE (or SKILLBUS_NETWORK=IFACE; docs/security.md, "
                   "docs/transport.md)");
}

DdsBus::DdsBus(const std::string& url) : url_(url), parsed_(parse_dds_url(url)) {
  check_dds_local(parsed_, url);
  // Private by default: our configuration, unless the user gave Cyclone one where the
  // network is allowed ($SKILLBUS_NETWORK): one inherited from elsewhere (a ROS 2 shell)
  // would put the robot's bus on the network. $SKILLBUS_DDS_CONFIG records ours, so that a
  // child that inherits both knows it is not the user's. As skillbus.dds.cyclone_config.
  const char* given_env = std::getenv("CYCLONEDDS_URI");
  const char* own_env = std::getenv("SKILLBUS_DDS_CONFIG");
  const std::string given = given_env ? given_env : "", own = own_env ? own_env : "";
  if (!given.empty() && given != own) {
    const char* allowed = std::getenv("SKILLBUS_NETWORK");
    if (!allowed || !*allowed)
      throw BusError("bus URL '" + url + "': $CYCLONEDDS_URI is set (" + given.substr(0, 80) +
                     (given.size() > 80 ? "..." : "") +
                     "), and Cyclone would use it as it is, which may reach other hosts. skillbus stays on this "
                     "host unless told otherwise: unset it (skillbus then configures Cyclone for this host), or "
                     "allow the network with --network IFACE (SKILLBUS_NETWORK=IFACE; docs/transport.md)");
  } else {
    const std::string xml = dds_config_xml(parsed_);
    setenv("CYCLONEDDS_URI", xml.c_str(), 1);
    setenv("SKILLBUS_DDS_CONFIG", xml.c_str(), 1);
  }
  participant_ = dds_create_participant(static_cast<dds_domainid_t>(parsed_.domain), nullptr, nullptr);
  if (participant_ < 0)
    throw BusError("bus URL '" + url + "': cannot join DDS domain " + std::to_string(parsed_.domain) + ": " +
                   dds_error(participant_));
  waitset_ = dds_create_waitset(participant_);
  if (waitset_ < 0) throw BusError("DDS waitset: " + dds_error(waitset_));
}

DdsBus::~DdsBus() {
  if (participant_ > 0) dds_delete(participant_);  // (deletes everything it made)
}

dds_qos_t* DdsBus::qos(const std::string& channel) const {
  dds_qos_t* q = dds_create_qos();
  if (is_state(channel)) {
    dds_qset_reliability(q, parsed_.state_best_effort ? DDS_RELIABILITY_BEST_EFFORT : DDS_RELIABILITY_RELIABLE,
                         DDS_SECS(1));
    dds_qset_history(q, DDS_HISTORY_KEEP_LAST, kStateDepth);
  } else {
    dds_qset_reliability(q, DDS_RELIABILITY_RELIABLE, DDS_SECS(1));
    dds_qset_history(q, DDS_HISTORY_KEEP_ALL, 0);
  }
  // Transient-local with a short history for late joiners: DDS matches a new writer with
  // its readers some time after it is made, and a volatile writer's first samples would
  // miss readers that existed (LCM delivers to every subscriber at once). The reader
  // drops what was written long before it (take_one).
  dds_qset_durability(q, DDS_DURABILITY_TRANSIENT_LOCAL);
  dds_qset_durability_service(q, 0, DDS_HISTORY_KEEP_LAST, kLateJoinerDepth, DDS_LENGTH_UNLIMITED, DDS_LENGTH_UNLIMITED,
                              DDS_LENGTH_UNLIMITED);
  return q;
}

dds_entity_t DdsBus::topic(const std::string& channel) {
  auto it = topics_.find(channel);
  if (it != topics_.end()) return it->second;
  refuse_long_channel(channel);  // (DDS would carry it; LCM, the other transport, would not)
  dds_qos_t* q = qos(channel);
  if (channel.find_first_of(".*+?[](){}|^$\\") != std::string::npos) {
    dds_delete_qos(q);
    throw BusError("DDS topic '" + channel + "': a channel name, not a pattern (DDS has no LCM-style regular-"
                   "expression subscriptions: subscribe to each channel)");
  }
  const dds_entity_t t = dds_create_topic(participant_, &skillbus_Envelope_desc, channel.c_str(), q, nullptr);
  dds_delete_qos(q);
  if (t < 0) throw BusError("DDS topic '" + channel + "': " + dds_error(t));
  topics_[channel] = t;
  return t;
}

void DdsBus::publish(const std::string& channel, const void* data, size_t size) {
  refuse_oversized(channel, size);  // (DDS would carry it; LCM, the other transport, would not)
  auto it = writers_.find(channel);
  if (it == writers_.end()) {
    dds_qos_t* q = qos(channel);
    const dds_entity_t w = dds_create_writer(participant_, topic(channel), q, nullptr);
    dds_delete_qos(q);
    if (w < 0) throw BusError("DDS writer for " + channel + ": " + dds_error(w));
    it = writers_.emplace(channel, w).first;
  }
  skillbus_Envelope e{};
  e.data._buffer = static_cast<uint8_t*>(const_cast<void*>(data));
  e.data._length = e.data._maximum = static_cast<uint32_t>(size);
  e.data._release = false;
  const dds_return_t r = dds_write(it->second, &e);
  if (r == DDS_RETCODE_TIMEOUT) {
    // A reliable writer waits (up to its blocking time) while a matched reader has not
    // taken what it holds: a stopped process, or a killed one until its lease ends. The
    // message is lost, as a datagram can be on LCM, and the protocols above notice and
    // retry (RPC, lockstep resends) or report it. Counted and logged, never fatal.
    ++lost_sends_;
    if (lost_sends_ <= 5 || lost_sends_ % 1000 == 0)
      SB_WARN("bus", "sending on " << channel << " timed out: a reader takes nothing (stopped, or killed and "
                                   << "still matched): message lost (#" << lost_sends_ << ")");
    return;
  }
  if (r < 0) throw BusError("DDS write on " + channel + " (" + std::to_string(size) + " bytes): " + dds_error(r));
}

int DdsBus::subscribe(const std::string& channel, Handler handler, int /*queue_capacity: DDS's history*/) {
  auto it = readers_.find(channel);
  if (it == readers_.end()) {
    Reader r;
    dds_qos_t* q = qos(channel);
    r.reader = dds_create_reader(participant_, topic(channel), q, nullptr);
    dds_delete_qos(q);
    if (r.reader < 0) throw BusError("DDS reader for " + channel + ": " + dds_error(r.reader));
    r.condition = dds_create_readcondition(r.reader, DDS_ANY_STATE);
    if (r.condition < 0 || dds_waitset_attach(waitset_, r.condition, r.condition) < 0)
      throw BusError("DDS read condition for " + channel);
    r.since = dds_time() - late_joiner_window(channel);
    it = readers_.emplace(channel, std::move(r)).first;
    order_.push_back(channel);
  }
  const int id = next_id_++;
  it->second.handlers[id] = std::move(handler);
  subs_[id] = channel;
  return id;
}

void DdsBus::unsubscribe(int id) {
  auto s = subs_.find(id);
  if (s == subs_.end()) return;
  auto r = readers_.find(s->second);
  subs_.erase(s);
  if (r == readers_.end()) return;
  r->second.handlers.erase(id);
  if (!r->second.handlers.empty()) return;
  // Nobody reads the channel here any more: the reader goes, and DDS stops sending it.
  dds_waitset_detach(waitset_, r->second.condition);
  dds_delete(r->second.reader);  // (deletes its condition)
  order_.erase(std::find(order_.begin(), order_.end(), r->first));
  readers_.erase(r);
}

bool DdsBus::take_one() {
  for (size_t i = 0; i < order_.size(); ++i) {
    const std::string channel = order_[i];
    Reader& r = readers_.at(channel);
    void* samples[1] = {nullptr};
    dds_sample_info_t info[1];
    const dds_return_t n = dds_take(r.reader, samples, info, 1, 1);
    if (n <= 0) continue;
    std::rotate(order_.begin() + static_cast<long>(i), order_.begin() + static_cast<long>(i) + 1, order_.end());
    Bytes payload;
    // (a late joiner's history from before we subscribed: LCM never had it)
    const bool valid = info[0].valid_data && info[0].source_timestamp >= r.since;
    if (valid) {
      const auto* e = static_cast<const skillbus_Envelope*>(samples[0]);
      payload.assign(e->data._buffer, e->data._buffer + e->data._length);
    }
    dds_return_loan(r.reader, samples, n);
    if (valid) {
      // Handlers may (un)subscribe, even this reader: a copy of the bytes and of the list.
      std::vector<Handler> hs;
      for (const auto& [id, h] : r.handlers) hs.push_back(h);
      for (const auto& h : hs) {
        try {
          h(channel, payload.data(), payload.size());
        } catch (const std::exception& ex) {
          if (++handler_failures_ <= 5 || handler_failures_ % 1000 == 0)
            SB_ERROR("bus", "handler for " << channel << " failed (#" << handler_failures_ << "): " << ex.what());
        }
      }
    }
    return true;
  }
  return false;
}

bool DdsBus::handle(std::chrono::milliseconds timeout) {
  const auto deadline = std::chrono::steady_clock::now() + timeout;
  for (;;) {
    if (take_one()) return true;
    caught_up_ = std::chrono::steady_clock::now();  // (nothing left to take)
    const auto left = deadline - caught_up_;
    if (left <= std::chrono::steady_clock::duration::zero()) return false;
    const auto ns = std::chrono::duration_cast<std::chrono::nanoseconds>(left).count();
    const dds_return_t r = dds_waitset_wait(waitset_, nullptr, 0, ns);
    if (r < 0) throw BusError("waiting on the DDS bus " + url_ + " failed: " + dds_error(r));
  }
}

}  // namespace skillbus
