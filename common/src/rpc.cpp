#include "skillbus/rpc.hpp"

#include <unistd.h>

#include <algorithm>
#include <random>
#include <set>

#include "skillbus_msgs/rpc_reply_t.hpp"
#include "skillbus_msgs/rpc_request_t.hpp"

namespace skillbus {
namespace {

using skillbus_msgs::rpc_reply_t;
using skillbus_msgs::rpc_request_t;

std::string upper(std::string s) {
  for (auto& c : s) c = static_cast<char>(std::toupper(static_cast<unsigned char>(c)));
  return s;
}

int64_t realtime_ns() {
  return std::chrono::duration_cast<std::chrono::nanoseconds>(std::chrono::system_clock::now().time_since_epoch())
      .count();
}

}  // namespace

std::string rpc_request_channel(const std::string& area) { return channel("SB_" + upper(area) + "_REQ"); }
std::string rpc_reply_channel(const std::string& area) { return channel("SB_" + upper(area) + "_REP"); }

// ---------------------------------------------------------------- server

RpcServer::RpcServer(Bus& bus, const std::string& area, size_t memory, size_t memory_bytes)
    : bus_(bus),
      area_(area),
      req_channel_(rpc_request_channel(area)),
      rep_channel_(rpc_reply_channel(area)),
      memory_(memory),
      memory_bytes_(memory_bytes),
      bad_("rpc-server " + area) {
  sub_ = bus_.subscribe(req_channel_, [this](const std::string& ch, const uint8_t* d, size_t n) { on_request(ch, d, n); });
}

RpcServer::~RpcServer() { bus_.unsubscribe(sub_); }

void RpcServer::add_raw_method(const std::string& name, RawMethod method) { methods_[name] = std::move(method); }

int32_t RpcServer::Answer::chunks() const {
  return payload.size() <= kRpcChunkBytes ? 1 : static_cast<int32_t>((payload.size() + kRpcChunkBytes - 1) / kRpcChunkBytes);
}

bool RpcServer::Answer::complete() const {
  return chunks() == 1 || std::all_of(sent.begin(), sent.end(), [](bool b) { return b; });
}

void RpcServer::send_chunk(Answer& a, int32_t chunk) {
  if (a.sent.size() != static_cast<size_t>(a.chunks())) a.sent.assign(static_cast<size_t>(a.chunks()), false);
  a.sent[static_cast<size_t>(chunk)] = true;
  rpc_reply_t rep{};
  rep.client_id = a.client_id;
  rep.request_id = a.request_id;
  rep.method = a.method;
  rep.status = a.status;
  rep.error = a.error;
  rep.chunk = chunk;
  rep.chunks = a.chunks();
  const size_t from = static_cast<size_t>(chunk) * kRpcChunkBytes;
  const size_t to = std::min(a.payload.size(), from + kRpcChunkBytes);
  if (from < to) rep.payload.assign(a.payload.begin() + static_cast<std::ptrdiff_t>(from),
                                    a.payload.begin() + static_cast<std::ptrdiff_t>(to));
  rep.payload_size = static_cast<int32_t>(rep.payload.size());
  const Bytes buf = encode_msg(rep);
  bus_.publish(rep_channel_, buf.data(), buf.size());
}

void RpcServer::on_request(const std::string& ch, const uint8_t* data, size_t size) {
  rpc_request_t req;
  if (!decode_msg(data, size, req)) {
    bad_.record(ch, "not an rpc_request_t", size);
    return;
  }
  const std::string key = req.client_id + '\n' + std::to_string(req.request_id);
  if (auto it = answered_.find(key); it != answered_.end()) {
    Answer& a = it->second;
    if (req.chunk == 0) {
      ++duplicates_;  // a retry: answer again from memory, do not run the method twice
    } else if (req.chunk > 0 && req.chunk < a.chunks()) {
      ++pulled_;  // the client asks for the next part of a large reply
    } else {
      bad_.record(ch, "chunk " + std::to_string(req.chunk) + " of a reply in " + std::to_string(a.chunks()), size);
      return;
    }
    send_chunk(a, req.chunk);
    return;
  }
  if (req.chunk == 0 && std::any_of(deferred_.begin(), deferred_.end(), [&](const auto& d) { return d.first == key; })) {
    ++duplicates_;  // a retry of a deferred call: it is answered when it can be
    return;
  }
  if (req.chunk == 0 && running_.count(key)) {
    // A retry of a call still running: a method that waits (a nested call pumps the bus)
    // would otherwise run twice. Its answer goes out when it ends.
    ++duplicates_;
    return;
  }
  Answer a;
  a.client_id = req.client_id;
  a.request_id = req.request_id;
  a.method = req.method;
  a.status = rpc_reply_t::OK;
  if (req.chunk != 0) {  // a part of a reply this server no longer has (or never had)
    a.status = rpc_reply_t::ERROR;
    a.error = area_ + "." + req.method + ": the reply is no longer remembered (larger replies than the server keeps, "
              "or the call is too old): call again";
    send_chunk(a, 0);
    return;
  }
  if (req.deadline_ns != 0 && realtime_ns() > req.deadline_ns) {
    ++expired_;  // the client has given up; running it now would surprise it
    return;
  }
  auto m = methods_.find(req.method);
  if (m == methods_.end()) {
    a.status = rpc_reply_t::UNKNOWN_METHOD;
    a.error = "unknown method '" + req.method + "' on " + area_;
  } else {
    running_.insert(key);
    struct Done {
      std::set<std::string>& running;
      const std::string& key;
      ~Done() { running.erase(key); }
    } done{running_, key};
    try {
      a.payload = m->second(req.payload.data(), req.payload.size());
    } catch (const RpcDefer&) {
      deferred_.emplace_back(key, std::make_pair(ch, Bytes(data, data + size)));
      while (deferred_.size() > kMaxDeferred) {
        bad_.record(ch, "too many deferred requests: the oldest was dropped", 0);
        deferred_.pop_front();
      }
      return;
    } catch (const RpcBadRequest& e) {
      a.status = rpc_reply_t::BAD_REQUEST;
      a.error = e.what();
    } catch (const std::exception& e) {
      a.status = rpc_reply_t::ERROR;
      a.error = area_ + "." + req.method + " failed: " + e.what();
    }
  }
  ++served_;
  send_chunk(a, 0);
  remember(key, std::move(a));
}

void RpcServer::retry_deferred() {
  auto pending = std::move(deferred_);
  deferred_.clear();
  for (const auto& [key, request] : pending) on_request(request.first, request.second.data(), request.second.size());
}

void RpcServer::remember(const std::string& key, Answer answer) {
  remembered_bytes_ += answer.payload.size() + answer.error.size() + 64;
  answered_[key] = std::move(answer);
  order_.push_back(key);
  // Bounded by count and by bytes: pages of a large world would otherwise keep megabytes
  // of replies that a retry within a call's timeout is the only use for. The newest is
  // kept whatever its size, and so, within twice the bytes, is an answer in chunks that a
  // client is still pulling (it would otherwise get "no longer remembered" halfway).
  while (order_.size() > memory_ || (remembered_bytes_ > memory_bytes_ && order_.size() > 1)) {
    auto victim = order_.begin();
    if (order_.size() <= memory_ && remembered_bytes_ <= 2 * memory_bytes_) {
      for (auto o = order_.begin(); o != std::prev(order_.end()); ++o)
        if (answered_.at(*o).complete()) {
          victim = o;
          break;
        }
    }
    auto it = answered_.find(*victim);
    remembered_bytes_ -= it->second.payload.size() + it->second.error.size() + 64;
    answered_.erase(it);
    order_.erase(victim);
  }
}

// ---------------------------------------------------------------- client

RpcClient::RpcClient(Bus& bus, const std::string& area, const std::string& client_name)
    : bus_(bus), area_(area), req_channel_(rpc_request_channel(area)), bad_("rpc-client " + area) {
  std::random_device rd;  // identity only: never part of anything hashed under lockstep
  char nonce[17];
  std::snprintf(nonce, sizeof nonce, "%08x%08x", rd(), rd());
  client_id_ = client_name + ":" + std::to_string(::getpid()) + ":" + nonce;
  sub_ = bus_.subscribe(rpc_reply_channel(area),
                        [this](const std::string& ch, const uint8_t* d, size_t n) { on_reply(ch, d, n); });
}

RpcClient::~RpcClient() { bus_.unsubscribe(sub_); }

void RpcClient::on_reply(const std::string& ch, const uint8_t* data, size_t size) {
  rpc_reply_t rep;
  if (!decode_msg(data, size, rep)) {
    bad_.record(ch, "not an rpc_reply_t", size);
    return;
  }
  if (rep.client_id != client_id_) return;
  auto it = pending_.find(rep.request_id);
  if (it == pending_.end() || it->second.done) return;
  Pending& p = it->second;
  if (rep.chunks <= 1 || rep.status != rpc_reply_t::OK) {  // the whole reply
    p.done = true;
    p.status = rep.status;
    p.error = rep.error;
    p.payload.assign(rep.payload.begin(), rep.payload.end());
    return;
  }
  // A part of a large reply. The first the client takes is chunk 0, the call's own answer
  // (the others come only when asked for), with a bounded count; parts of another size of
  // reply (a forged one) are ignored, and so is an empty part (every part has bytes).
  if (p.parts.empty()) {
    if (rep.chunk != 0) return;
    if (rep.chunks > kRpcMaxChunks) {
      p.done = true;
      p.status = rpc_reply_t::ERROR;
      p.error = "the reply of " + rep.method + " comes in " + std::to_string(rep.chunks) + " chunks, more than " +
                std::to_string(kRpcMaxChunks) + " (" + std::to_string(kRpcMaxChunks * kRpcChunkBytes >> 20) +
                " MB): refused";
      return;
    }
    p.parts.resize(static_cast<size_t>(rep.chunks));
  }
  if (static_cast<size_t>(rep.chunks) != p.parts.size() || rep.chunk < 0 || rep.chunk >= rep.chunks ||
      rep.payload.empty() || !p.parts[static_cast<size_t>(rep.chunk)].empty())
    return;
  p.parts[static_cast<size_t>(rep.chunk)].assign(rep.payload.begin(), rep.payload.end());
  if (++p.have < rep.chunks) return;
  for (const auto& part : p.parts) p.payload.insert(p.payload.end(), part.begin(), part.end());
  p.parts.clear();
  p.status = rep.status;
  p.done = true;
}

void RpcClient::pull_missing(const std::string& method, int64_t request_id, int64_t deadline_ns, const Pending& p) {
  rpc_request_t pull{};
  pull.client_id = client_id_;
  pull.request_id = request_id;
  pull.deadline_ns = deadline_ns;
  pull.method = method;
  int asked = 0;
  for (size_t k = 1; k < p.parts.size() && asked < kRpcPullWindow; ++k) {
    if (!p.parts[k].empty()) continue;
    pull.chunk = static_cast<int32_t>(k);
    const Bytes buf = encode_msg(pull);
    bus_.publish(req_channel_, buf.data(), buf.size());
    ++asked;
  }
}

void RpcClient::wait(std::chrono::milliseconds left) {
  if (!while_waiting_) {
    bus_.handle(left);
    return;
  }
  bus_.handle(std::min(left, std::chrono::milliseconds(200)));
  while_waiting_();
}

Bytes RpcClient::call_raw(const std::string& method, const Bytes& payload, const CallOptions& opts) {
  using clock = std::chrono::steady_clock;
  const auto start = clock::now();
  const auto deadline = start + opts.timeout;
  rpc_request_t req{};
  req.client_id = client_id_;
  req.request_id = next_request_id_++;
  req.deadline_ns = realtime_ns() + std::chrono::duration_cast<std::chrono::nanoseconds>(opts.timeout).count();
  req.method = method;
  req.payload.assign(payload.begin(), payload.end());
  req.payload_size = static_cast<int32_t>(req.payload.size());
  const Bytes buf = encode_msg(req);

  const int64_t rid = req.request_id;
  pending_[rid] = Pending{};
  auto done = [this, rid] { return pending_[rid].done; };
  int attempts = 0;
  while (!done()) {
    const auto now = clock::now();
    if (now >= deadline) break;
    if (!pending_[rid].parts.empty()) {
      // A large reply has begun: ask for the parts still missing, a window at a time, and
      // again after a retry interval for those that did not come.
      const int32_t had = pending_[rid].have;
      pull_missing(method, rid, req.deadline_ns, pending_[rid]);
      const auto again = std::min(deadline, now + opts.retry_interval);
      while (!done() && pending_[rid].have - had < kRpcPullWindow) {
        const auto left = std::chrono::duration_cast<std::chrono::milliseconds>(again - clock::now());
        if (left.count() <= 0) break;
        wait(left);
      }
      continue;
    }
    bus_.publish(req_channel_, buf.data(), buf.size());
    if (attempts++ > 0) ++retries_;
    // Back off (x2 per attempt, to 1 s) so that a reply lost to an overrun receiver is
    // not followed by a flood of resent large replies.
    const auto backoff = std::min<std::chrono::milliseconds>(std::chrono::milliseconds(1000),
                                                             opts.retry_interval * (1 << std::min(attempts - 1, 10)));
    const auto resend_at = std::min(deadline, now + backoff);
    while (!done() && pending_[rid].parts.empty()) {
      const auto left = std::chrono::duration_cast<std::chrono::milliseconds>(resend_at - clock::now());
      if (left.count() <= 0) break;
      wait(left);
    }
  }
  Pending result = std::move(pending_[rid]);
  pending_.erase(rid);
  if (!result.done && !result.parts.empty()) {
    const double secs = std::chrono::duration<double>(opts.timeout).count();
    throw RpcTimeout("rpc " + area_ + "." + method + ": " + std::to_string(result.have) + " of the " +
                     std::to_string(result.parts.size()) + " parts of its reply came on " + rpc_reply_channel(area_) +
                     " within " + std::to_string(secs).substr(0, 5) + " s");
  }
  if (!result.done) {
    const double secs = std::chrono::duration<double>(opts.timeout).count();
    throw RpcTimeout("rpc " + area_ + "." + method + ": no reply on " + rpc_reply_channel(area_) + " within " +
                     std::to_string(secs).substr(0, 5) + " s (" + std::to_string(attempts) + " attempts)");
  }
  if (result.status != rpc_reply_t::OK) throw RpcRemoteError(result.status, result.error);
  return result.payload;
}

}  // namespace skillbus
