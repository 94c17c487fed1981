// Message authentication on the bus: only holders of the deployment's key command the
// robot. The same trailer, HMAC and rules as py_skills/skillbus/auth.py (the format is
// described there and in docs/security.md); OpenSSL computes the HMAC-SHA256.
//
// open_bus() wraps its backend in an AuthenticatedBus when there is a key file (key_path())
// (and enforces $SKILLBUS_POLICY_FILE, who may send on which channel, when set).
// Handlers then see only messages that verify, with the trailer stripped: unsigned,
// forged, stale, replayed and forbidden ones are dropped and counted.
#pragma once

#include <array>
#include <cstdint>
#include <map>
#include <memory>
#include <string>
#include <unordered_map>
#include <utility>
#include <vector>

#include "skillbus/bus.hpp"

namespace skillbus::auth {

constexpr const char* kKeyEnv = "SKILLBUS_KEY_FILE";
constexpr const char* kIdentityEnv = "SKILLBUS_IDENTITY";
constexpr const char* kPolicyEnv = "SKILLBUS_POLICY_FILE";
constexpr double kWindowSeconds = 30.0;
constexpr uint64_t kReplayWindow = 4096;
constexpr size_t kMaxSenders = 4096;

using Key = std::vector<uint8_t>;

// The keys of a key file (one hex line each, the signing key first); throws BusError
// naming the file and the fix for a missing, malformed or group/world-accessible file.
std::vector<Key> load_keys(const std::string& path);

// Who may send on which channel (the same file format as skillbus.policy).
class Policy {
 public:
  static Policy parse(const std::string& text, const std::string& source);  // throws BusError
  static Policy load(const std::string& path);                              // throws BusError
  bool allows(const std::string& identity, const std::string& channel) const;
  const std::string& source() const { return source_; }  // the file it came from

 private:
  std::string source_;
  struct Rule {
    std::string pattern;
    std::vector<std::string> identities;
  };
  std::vector<Rule> rules_;
  std::string namespace_;
};
bool glob_match(const std::string& pattern, const std::string& name);  // '*' = any characters

// Appends the trailer to what one process publishes.
class Sealer {
 public:
  Sealer(Key key, std::string identity);
  Bytes seal(const std::string& channel, const void* data, size_t size);
  uint64_t incarnation() const { return incarnation_; }

 private:
  Key key_;
  std::string identity_;
  uint64_t incarnation_;
  uint64_t counter_ = 0;
};

// The size of the payload in front of a well-formed trailer, unverified: for deciding who
// is to verify and act on a message, never for acting on it. False without one.
bool unverified_payload_size(const uint8_t* data, size_t size, size_t& payload_size);

enum class Reason { Unsigned, BadMac, Stale, Replayed, Forbidden };
const char* reason_name(Reason r);

struct Stats {
  uint64_t ok = 0;
  std::map<std::string, uint64_t> rejected;  // by reason_name
  uint64_t total_rejected() const;
};

// Verifies and strips trailers; keeps the replay windows.
class Opener {
 public:
  explicit Opener(std::vector<Key> keys, std::shared_ptr<const Policy> policy = nullptr);
  // On success: the payload's size (the payload is data[0, size)), and the sender's
  // identity. On failure: false, `why` set, counted.
  bool open(const std::string& channel, const uint8_t* data, size_t size, size_t& payload_size,
            std::string& identity, Reason& reason, std::string& why);
  const Stats& stats() const { return stats_; }
  int64_t (*clock_ns)() = nullptr;  // tests: a fake wall clock

 private:
  struct Window {
    uint64_t highest = 0;
    std::vector<uint64_t> seen;  // bit i of the bitset: counter highest - i seen
    int64_t heard = 0;
  };
  bool check_replay(const std::string& identity, uint64_t incarnation, uint64_t counter, int64_t now);
  void forget(int64_t now);
  std::vector<Key> keys_;
  std::shared_ptr<const Policy> policy_;
  Stats stats_;
  std::map<std::pair<std::string, uint64_t>, Window> windows_;
};

// A Bus that signs what it publishes and verifies what it delivers.
class AuthenticatedBus : public Bus {
 public:
  AuthenticatedBus(std::unique_ptr<Bus> inner, std::vector<Key> keys, std::string identity,
                   std::shared_ptr<const Policy> policy);
  // Throws BusError when the policy does not let this identity send on the channel:
  // every receiver would drop the message, and a lockstep frame would then wait for it
  // and fail as "message lost"; refused here, the sender names the rule it lacks.
  void publish(const std::string& channel, const void* data, size_t size) override;
  int subscribe(const std::string& channel, Handler handler, int queue_capacity = 10000) override;
  void unsubscribe(int subscription_id) override { inner_->unsubscribe(subscription_id); }
  bool handle(std::chrono::milliseconds timeout) override {
    verified_.clear();
    const bool handled = inner_->handle(timeout);
    verified_.clear();
    return handled;
  }
  std::string url() const override { return inner_->url(); }
  std::chrono::steady_clock::time_point caught_up_at() const override { return inner_->caught_up_at(); }
  const Stats& stats() const { return opener_.stats(); }
  const std::string& identity() const { return identity_; }

 private:
  void note(Reason r, const std::string& identity, const std::string& why);
  std::unique_ptr<Bus> inner_;
  std::string identity_;
  std::shared_ptr<const Policy> policy_;  // (also the opener's) for what this process sends
  std::unordered_map<std::string, bool> may_send_;  // the policy's answer per channel sent on
  bool may_send(const std::string& channel);  // the policy's answer, remembered
  Sealer sealer_;
  Opener opener_;
  std::map<std::pair<int, std::string>, std::pair<int64_t, uint64_t>> last_log_;  // -> (when, quiet since)
  std::map<std::string, long> verified_;  // this handle()'s datagrams: payload size, -1 refused
};

// The key file this process uses: $SKILLBUS_KEY_FILE ("none": no key), else
// $XDG_CONFIG_HOME (or ~/.config)/skillbus/bus.key when it exists, else "" (an open bus).
std::string key_path();

// The bus's authentication counters, or nullptr when it does not authenticate.
const Stats* stats_of(const Bus& bus);

// `inner` behind the key of $SKILLBUS_KEY_FILE (and the policy of $SKILLBUS_POLICY_FILE),
// or `inner` itself without a key (one warning per process).
std::unique_ptr<Bus> authenticated(std::unique_ptr<Bus> inner);

}  // namespace skillbus::auth
