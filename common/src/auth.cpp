// Message authentication (skillbus/auth.hpp): the C++ twin of py_skills/skillbus/auth.py.
// Both produce and accept the same bytes; tests/integration/test_security.py checks that
// across the languages.
#include "skillbus/auth.hpp"

// SHA256_Init and friends are deprecated in OpenSSL 3 in favour of EVP, whose per-message
// heap copies are what this file avoids (see KeyedMac); they remain in OpenSSL 3.
#define OPENSSL_SUPPRESS_DEPRECATED
#include <openssl/crypto.h>
#include <openssl/sha.h>
#include <sys/stat.h>
#include <unistd.h>

#include <algorithm>
#include <cctype>
#include <chrono>
#include <cstdlib>
#include <cstring>
#include <fstream>
#include <mutex>
#include <sstream>

#include "skillbus/log.hpp"

namespace skillbus::auth {

namespace {

constexpr const char kLog[] = "bus";
constexpr uint8_t kMagic[4] = {'S', 'B', 'A', '1'};
constexpr char kTag[] = "skillbus-auth-v1";
constexpr size_t kMacSize = 32;
constexpr size_t kFixed = 24;  // incarnation, counter, time_ns: u64 little-endian each

int64_t wall_ns() {
  return std::chrono::duration_cast<std::chrono::nanoseconds>(std::chrono::system_clock::now().time_since_epoch())
      .count();
}

void put_u64(Bytes& b, uint64_t v) {
  for (int i = 0; i < 8; ++i) b.push_back(uint8_t(v >> (8 * i)));
}

uint64_t get_u64(const uint8_t* p) {
  uint64_t v = 0;
  for (int i = 0; i < 8; ++i) v |= uint64_t(p[i]) << (8 * i);
  return v;
}

// HMAC-SHA256 (RFC 2104) with the key's two padded blocks hashed once per key: a message's
// MAC is then two copies of a SHA-256 state and the hashing of the message itself, with no
// allocation. (OpenSSL 3's EVP_MAC duplicates its context on the heap for every message:
// a third of a lockstep master's CPU at 8 participants went there.) The same bytes as
// Python's hmac; tests/py/test_auth.py and the cross-language tests check it.
class KeyedMac {
 public:
  explicit KeyedMac(const Key& key) {
    uint8_t block[64] = {};
    if (key.size() > sizeof(block)) {
      SHA256(key.data(), key.size(), block);  // a long key is hashed first
    } else {
      std::memcpy(block, key.data(), key.size());
    }
    uint8_t pad[64];
    for (size_t i = 0; i < 64; ++i) pad[i] = block[i] ^ 0x36;
    if (SHA256_Init(&inner_) != 1 || SHA256_Update(&inner_, pad, 64) != 1)
      throw BusError("OpenSSL SHA-256 unavailable");
    for (size_t i = 0; i < 64; ++i) pad[i] = block[i] ^ 0x5c;
    if (SHA256_Init(&outer_) != 1 || SHA256_Update(&outer_, pad, 64) != 1)
      throw BusError("OpenSSL SHA-256 unavailable");
    OPENSSL_cleanse(block, sizeof(block));
    OPENSSL_cleanse(pad, sizeof(pad));
  }
  ~KeyedMac() {
    OPENSSL_cleanse(&inner_, sizeof(inner_));
    OPENSSL_cleanse(&outer_, sizeof(outer_));
  }
  KeyedMac(const KeyedMac&) = delete;
  KeyedMac& operator=(const KeyedMac&) = delete;
  const SHA256_CTX& inner() const { return inner_; }
  const SHA256_CTX& outer() const { return outer_; }

 private:
  SHA256_CTX inner_{}, outer_{};
};

const KeyedMac& keyed(const Key& key) {
  static std::map<Key, std::unique_ptr<KeyedMac>> cache;  // (a process has one or two keys)
  static std::mutex mutex;  // (skillbus_native verifies without Python's lock on one thread)
  std::lock_guard<std::mutex> lock(mutex);
  auto& slot = cache[key];
  if (!slot) slot = std::make_unique<KeyedMac>(key);
  return *slot;
}

// HMAC-SHA256(key, tag | u16 channel length | channel | u32 payload length | payload | fields)
std::array<uint8_t, kMacSize> mac(const Key& key, const std::string& channel, const uint8_t* payload, size_t size,
                                  const uint8_t* fields, size_t fields_size) {
  const KeyedMac& k = keyed(key);
  const auto ch = static_cast<uint16_t>(channel.size());
  const uint8_t ch_len[2] = {uint8_t(ch), uint8_t(ch >> 8)};
  const auto n = static_cast<uint32_t>(size);
  const uint8_t size_le[4] = {uint8_t(n), uint8_t(n >> 8), uint8_t(n >> 16), uint8_t(n >> 24)};
  SHA256_CTX c = k.inner();
  std::array<uint8_t, kMacSize> out{};
  const bool ok = SHA256_Update(&c, kTag, sizeof(kTag) - 1) == 1 && SHA256_Update(&c, ch_len, 2) == 1 &&
                  SHA256_Update(&c, channel.data(), channel.size()) == 1 && SHA256_Update(&c, size_le, 4) == 1 &&
                  SHA256_Update(&c, payload, size) == 1 && SHA256_Update(&c, fields, fields_size) == 1 &&
                  SHA256_Final(out.data(), &c) == 1;
  c = k.outer();
  if (!ok || SHA256_Update(&c, out.data(), out.size()) != 1 || SHA256_Final(out.data(), &c) != 1)
    throw BusError("OpenSSL SHA-256 failed");
  OPENSSL_cleanse(&c, sizeof(c));
  return out;
}

std::string default_identity() {
  const char* env = std::getenv(kIdentityEnv);
  if (env && *env) return env;
  std::ifstream comm("/proc/self/comm");  // the program's name
  std::string name;
  std::getline(comm, name);
  return name.empty() ? "cpp" : name;
}

}  // namespace

std::vector<Key> load_keys(const std::string& path) {
  struct stat st {};
  if (::stat(path.c_str(), &st) != 0)
    throw BusError("the bus key " + path + ": " + std::strerror(errno) + " (create one with: skillbus key create --path " +
                   path + ")");
  if (st.st_mode & 077) {
    std::ostringstream mode;
    mode << std::oct << (st.st_mode & 0777);
    throw BusError("the bus key " + path + " is readable or writable by others (mode " + mode.str() + "): chmod 600 " +
                   path);
  }
  std::ifstream in(path);
  if (!in) throw BusError("the bus key " + path + ": cannot read it");
  std::vector<Key> keys;
  std::string line;
  int n = 0;
  while (std::getline(in, line)) {
    ++n;
    const auto b = line.find_first_not_of(" \t\r");
    if (b == std::string::npos || line[b] == '#') continue;
    const auto e = line.find_last_not_of(" \t\r");
    const std::string hex = line.substr(b, e - b + 1);
    if (hex.size() % 2 != 0 || hex.find_first_not_of("0123456789abcdefABCDEF") != std::string::npos)
      throw BusError("the bus key " + path + ", line " + std::to_string(n) + ": not hexadecimal");
    Key k;
    for (size_t i = 0; i < hex.size(); i += 2) k.push_back(static_cast<uint8_t>(std::stoi(hex.substr(i, 2), nullptr, 16)));
    if (k.size() < 16)
      throw BusError("the bus key " + path + ", line " + std::to_string(n) + ": " + std::to_string(k.size()) +
                     " bytes, at least 16 needed");
    keys.push_back(std::move(k));
  }
  if (keys.empty()) throw BusError("the bus key " + path + " holds no key");
  return keys;
}

bool glob_match(const std::string& p, const std::string& s) {
  // Iterative '*' matching with backtracking to the last star (linear in practice).
  size_t i = 0, j = 0, star = std::string::npos, mark = 0;
  while (j < s.size()) {
    if (i < p.size() && p[i] != '*' && p[i] == s[j]) {
      ++i, ++j;
    } else if (i < p.size() && p[i] == '*') {
      star = i++, mark = j;
    } else if (star != std::string::npos) {
      i = star + 1, j = ++mark;
    } else {
      return false;
    }
  }
  while (i < p.size() && p[i] == '*') ++i;
  return i == p.size();
}

Policy Policy::parse(const std::string& text, const std::string& source) {
  Policy out;
  out.source_ = source;
  const char* ns = std::getenv("SKILLBUS_NAMESPACE");
  out.namespace_ = ns ? ns : "";
  std::istringstream in(text);
  std::string line;
  int n = 0;
  while (std::getline(in, line)) {
    ++n;
    const std::string body = line.substr(0, line.find('#'));
    std::istringstream words(body);
    Rule r;
    if (!(words >> r.pattern)) continue;
    for (std::string w; words >> w;) {
      if (w.size() > 255)
        throw BusError(source + ", line " + std::to_string(n) + ": the identity '" + w.substr(0, 40) +
                       "...' is longer than 255 bytes, which no sender can have (the trailer's room)");
      r.identities.push_back(w);
    }
    if (r.identities.empty())
      throw BusError(source + ", line " + std::to_string(n) + ": '" + r.pattern +
                     "' names a channel and no identity (a rule is CHANNEL IDENTITY...; * for any holder of the key)");
    for (char c : r.pattern)
      if (!(std::isalnum(static_cast<unsigned char>(c)) || c == '_' || c == '*' || c == '/'))
        throw BusError(source + ", line " + std::to_string(n) + ": '" + r.pattern +
                       "' is not a channel name or pattern (letters, digits, _, / and *)");
    out.rules_.push_back(std::move(r));
  }
  return out;
}

Policy Policy::load(const std::string& path) {
  std::ifstream in(path);
  if (!in) throw BusError("the bus policy " + path + ": " + std::strerror(errno));
  std::stringstream text;
  text << in.rdbuf();
  return parse(text.str(), path);
}

bool Policy::allows(const std::string& identity, const std::string& channel) const {
  std::string name = channel;
  if (!namespace_.empty() && name.compare(0, namespace_.size(), namespace_) == 0) name = name.substr(namespace_.size());
  // A robot's own channel ("r2/SB_ROBOT_ARM_CMD"): a pattern without a robot ("SB_ROBOT_*")
  // is about that channel of every robot; one with a robot ("r2/SB_ROBOT_*") about that robot's.
  const auto slash = name.find('/');
  const std::string base = slash == std::string::npos ? name : name.substr(slash + 1);
  for (const auto& r : rules_) {
    if (!glob_match(r.pattern, r.pattern.find('/') == std::string::npos ? base : name)) continue;
    for (const auto& id : r.identities)
      if (id == "*" || id == identity) return true;
    return false;
  }
  return false;
}

Sealer::Sealer(Key key, std::string identity)
    : key_(std::move(key)), identity_(std::move(identity)), incarnation_(static_cast<uint64_t>(wall_ns())) {
  // Cut, it would be another identity, which the policy forbids everywhere: refused, named.
  if (identity_.empty() || identity_.size() > 255)
    throw BusError("the bus identity '" + identity_.substr(0, 40) + (identity_.size() > 40 ? "..." : "") + "' is " +
                   std::to_string(identity_.size()) + " bytes: an identity is 1 to 255 bytes ($" + kIdentityEnv + ")");
}

Bytes Sealer::seal(const std::string& channel, const void* data, size_t size) {
  const auto* payload = static_cast<const uint8_t*>(data);
  Bytes out(payload, payload + size);
  const size_t fields_at = out.size();
  out.push_back(static_cast<uint8_t>(identity_.size()));
  out.insert(out.end(), identity_.begin(), identity_.end());
  put_u64(out, incarnation_);
  put_u64(out, ++counter_);
  put_u64(out, static_cast<uint64_t>(wall_ns()));
  const auto m = mac(key_, channel, out.data(), size, out.data() + fields_at, out.size() - fields_at);
  out.insert(out.end(), m.begin(), m.end());
  const auto body = static_cast<uint16_t>(out.size() - fields_at);
  out.push_back(uint8_t(body));
  out.push_back(uint8_t(body >> 8));
  out.insert(out.end(), kMagic, kMagic + 4);
  return out;
}

const char* reason_name(Reason r) {
  switch (r) {
    case Reason::Unsigned: return "unsigned";
    case Reason::BadMac: return "bad_mac";
    case Reason::Stale: return "stale";
    case Reason::Replayed: return "replayed";
    case Reason::Forbidden: return "forbidden";
  }
  return "?";
}

uint64_t Stats::total_rejected() const {
  uint64_t n = 0;
  for (const auto& [_, v] : rejected) n += v;
  return n;
}

Opener::Opener(std::vector<Key> keys, std::shared_ptr<const Policy> policy)
    : keys_(std::move(keys)), policy_(std::move(policy)) {}

bool unverified_payload_size(const uint8_t* data, size_t size, size_t& payload_size) {
  if (size < 6 || std::memcmp(data + size - 4, kMagic, 4) != 0) return false;
  const size_t body = size_t(data[size - 6]) | (size_t(data[size - 5]) << 8);
  if (body < 1 + kFixed + kMacSize || body > size - 6) return false;
  const size_t start = size - 6 - body;
  if (1 + size_t(data[start]) + kFixed + kMacSize != body) return false;
  payload_size = start;
  return true;
}

bool Opener::open(const std::string& channel, const uint8_t* data, size_t size, size_t& payload_size,
                  std::string& identity, Reason& reason, std::string& why) {
  auto reject = [&](Reason r, std::string text) {
    reason = r;
    why = std::move(text);
    stats_.rejected[reason_name(r)] += 1;
    return false;
  };
  if (size < 6 || std::memcmp(data + size - 4, kMagic, 4) != 0)
    return reject(Reason::Unsigned, "no authenticator on " + channel + " (" + std::to_string(size) + " bytes)");
  const size_t body = size_t(data[size - 6]) | (size_t(data[size - 5]) << 8);
  if (body < 1 + kFixed + kMacSize || body > size - 6)
    return reject(Reason::Unsigned, "a malformed authenticator on " + channel);
  const size_t start = size - 6 - body;
  const uint8_t* fields = data + start;
  const size_t id_len = fields[0];
  if (1 + id_len + kFixed + kMacSize != body) return reject(Reason::Unsigned, "a malformed authenticator on " + channel);
  const size_t fields_size = body - kMacSize;
  const uint8_t* got = fields + fields_size;
  bool verified = false;
  for (const auto& k : keys_) {
    const auto want = mac(k, channel, data, start, fields, fields_size);
    if (CRYPTO_memcmp(want.data(), got, kMacSize) == 0) verified = true;
  }
  if (!verified)
    return reject(Reason::BadMac, "the authenticator of a message on " + channel + " does not verify (another key?)");
  identity.assign(reinterpret_cast<const char*>(fields + 1), id_len);
  const uint64_t incarnation = get_u64(fields + 1 + id_len);
  const uint64_t counter = get_u64(fields + 1 + id_len + 8);
  const auto sent = static_cast<int64_t>(get_u64(fields + 1 + id_len + 16));
  const int64_t now = clock_ns ? clock_ns() : wall_ns();
  const double off_s = double(now - sent) / 1e9;
  if (off_s > kWindowSeconds || off_s < -kWindowSeconds)
    return reject(Reason::Stale, identity + " on " + channel + ": sent " + std::to_string(off_s) + " s from now");
  if (policy_ && !policy_->allows(identity, channel))
    return reject(Reason::Forbidden, identity + " may not send on " + channel);
  if (!check_replay(identity, incarnation, counter, now))
    return reject(Reason::Replayed, identity + " on " + channel + ": message " + std::to_string(counter) + " seen before");
  payload_size = start;
  stats_.ok += 1;
  return true;
}

bool Opener::check_replay(const std::string& identity, uint64_t incarnation, uint64_t counter, int64_t now) {
  constexpr size_t kWords = kReplayWindow / 64;
  auto [it, fresh] = windows_.try_emplace({identity, incarnation});
  Window& w = it->second;
  w.heard = now;
  if (fresh) {
    w.highest = counter;
    w.seen.assign(kWords, 0);
    w.seen[0] = 1;
    forget(now);
    return true;
  }
  auto test = [&](uint64_t age) { return (w.seen[age / 64] >> (age % 64)) & 1; };
  auto set = [&](uint64_t age) { w.seen[age / 64] |= uint64_t(1) << (age % 64); };
  if (counter > w.highest) {
    const uint64_t shift = counter - w.highest;
    if (shift >= kReplayWindow) {
      std::fill(w.seen.begin(), w.seen.end(), 0);
    } else {  // age i becomes age i + shift: the bitset shifted towards higher words
      const size_t words = shift / 64, bits = shift % 64;
      for (size_t i = kWords; i-- > 0;) {
        uint64_t v = i >= words ? w.seen[i - words] << bits : 0;
        if (bits && i >= words + 1) v |= w.seen[i - words - 1] >> (64 - bits);
        w.seen[i] = v;
      }
    }
    w.highest = counter;
    set(0);
    return true;
  }
  const uint64_t age = w.highest - counter;
  if (age >= kReplayWindow || test(age)) return false;
  set(age);
  return true;
}

void Opener::forget(int64_t now) {
  // A sender silent for longer than the window can be forgotten: any message of its
  // from before is stale by now. At most kMaxSenders are kept (the longest silent go).
  const auto horizon = now - static_cast<int64_t>(kWindowSeconds * 1e9);
  for (auto it = windows_.begin(); it != windows_.end();) it = it->second.heard < horizon ? windows_.erase(it) : std::next(it);
  while (windows_.size() > kMaxSenders) {
    auto oldest = windows_.begin();
    for (auto it = windows_.begin(); it != windows_.end(); ++it)
      if (it->second.heard < oldest->second.heard) oldest = it;
    windows_.erase(oldest);
  }
}

AuthenticatedBus::AuthenticatedBus(std::unique_ptr<Bus> inner, std::vector<Key> keys, std::string identity,
                                   std::shared_ptr<const Policy> policy)
    : inner_(std::move(inner)),
      identity_(std::move(identity)),
      policy_(policy),
      sealer_(keys.front(), identity_),
      opener_(std::move(keys), std::move(policy)) {}

void AuthenticatedBus::publish(const std::string& channel, const void* data, size_t size) {
  if (policy_ && !may_send(channel))
    throw BusError("the bus policy " + policy_->source() + " does not let '" + identity_ + "' send on " + channel +
                   ": every receiver would drop it (add a rule for it; docs/security.md)");
  const Bytes sealed = sealer_.seal(channel, data, size);
  inner_->publish(channel, sealed.data(), sealed.size());
}

bool AuthenticatedBus::may_send(const std::string& channel) {
  if (auto it = may_send_.find(channel); it != may_send_.end()) return it->second;
  if (may_send_.size() > 4096) may_send_.clear();  // (a process sends on few channels; bounded anyway)
  return may_send_[channel] = policy_->allows(identity_, channel);
}

int AuthenticatedBus::subscribe(const std::string& channel, Handler handler, int queue_capacity) {
  return inner_->subscribe(
      channel,
      [this, handler = std::move(handler)](const std::string& ch, const uint8_t* data, size_t size) {
        // One datagram reaches every subscription it matches within one handle(): it is
        // verified once (a second check would call it a replay); a replay is another
        // datagram, in a later handle().
        const size_t tail = std::min<size_t>(size, 38);
        std::string key = ch;
        key.push_back('\0');
        key.append(reinterpret_cast<const char*>(data + size - tail), tail);
        auto it = verified_.find(key);
        if (it == verified_.end()) {
          size_t payload = 0;
          std::string identity, why;
          Reason reason{};
          const bool ok = opener_.open(ch, data, size, payload, identity, reason, why);
          if (!ok) note(reason, identity, why);
          it = verified_.emplace(std::move(key), ok ? static_cast<long>(payload) : -1L).first;
        }
        if (it->second >= 0) handler(ch, data, static_cast<size_t>(it->second));
      },
      queue_capacity);
}

void AuthenticatedBus::note(Reason r, const std::string& identity, const std::string& why) {
  // At most one line per reason and sender every 10 s, with how many were not shown; the
  // text is escaped by log_line (it comes from the wire).
  const int64_t now = std::chrono::duration_cast<std::chrono::nanoseconds>(
                          std::chrono::steady_clock::now().time_since_epoch())
                          .count();
  auto& [when, quiet] = last_log_[{static_cast<int>(r), identity}];
  if (when != 0 && now - when < 10'000'000'000) {
    ++quiet;
    return;
  }
  const uint64_t more = quiet;
  when = now;
  quiet = 0;
  SB_WARN(kLog, "dropped " << reason_name(r) << ": " << why
                           << (more ? " (and " + std::to_string(more) + " more like it)" : std::string()));
}

const Stats* stats_of(const Bus& bus) {
  const auto* a = dynamic_cast<const AuthenticatedBus*>(&bus);
  return a ? &a->stats() : nullptr;
}

std::string key_path() {
  if (const char* env = std::getenv(kKeyEnv); env && *env) return std::string(env) == "none" ? "" : env;
  std::string base;
  if (const char* x = std::getenv("XDG_CONFIG_HOME"); x && *x) base = x;
  else if (const char* h = std::getenv("HOME"); h && *h) base = std::string(h) + "/.config";
  if (base.empty()) return "";
  const std::string path = base + "/skillbus/bus.key";
  return ::access(path.c_str(), F_OK) == 0 ? path : "";
}

std::unique_ptr<Bus> authenticated(std::unique_ptr<Bus> inner) {
  const std::string path = key_path();
  if (path.empty()) {
    static bool warned = false;
    if (!warned) {
      warned = true;
      SB_WARN(kLog, "no bus key (neither $" << kKeyEnv
                                            << " nor ~/.config/skillbus/bus.key): messages are neither signed nor "
                                               "checked; any process that reaches the bus can command this robot "
                                               "(skillbus key create; docs/security.md)");
    }
    return inner;
  }
  std::vector<Key> keys = load_keys(path);
  std::shared_ptr<const Policy> policy;
  if (const char* p = std::getenv(kPolicyEnv); p && *p) policy = std::make_shared<const Policy>(Policy::load(p));
  return std::make_unique<AuthenticatedBus>(std::move(inner), std::move(keys), default_identity(), std::move(policy));
}

}  // namespace skillbus::auth
