#include "skillbus/rpc.hpp"

#include <unistd.h>

#include <random>

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

void RpcServer::on_request(const std::string& ch, const uint8_t* data, size_t size) {
  rpc_request_t req;
  if (!decode_msg(data, size, req)) {
    bad_.record(ch, "not an rpc_request_t", size);
    return;
  }
  const std::string key = req.client_id + '\n' + std::to_string(req.request_id);
  if (auto it = answered_.find(key); it != answered_.end()) {
    ++duplicates_;  // a retry: answer again from memory, do not run the method twice
    bus_.publish(rep_channel_, it->second.data(), it->second.size());
    return;
  }
  if (req.deadline_ns != 0 && realtime_ns() > req.deadline_ns) {
    ++expired_;  // the client has given up; running it now would surprise it
    return;
  }
  rpc_reply_t rep{};
  rep.client_id = req.client_id;
  rep.request_id = req.request_id;
  rep.method = req.method;
  rep.status = rpc_reply_t::OK;
  auto m = methods_.find(req.method);
  if (m == methods_.end()) {
    rep.status = rpc_reply_t::UNKNOWN_METHOD;
    rep.error = "unknown method '" + req.method + "' on " + area_;
  } else {
    try {
      Bytes out = m->second(req.payload.data(), req.payload.size());
      rep.payload.assign(out.begin(), out.end());
    } catch (const RpcBadRequest& e) {
      rep.status = rpc_reply_t::BAD_REQUEST;
      rep.error = e.what();
    } catch (const std::exception& e) {
      rep.status = rpc_reply_t::ERROR;
      rep.error = area_ + "." + req.method + " failed: " + e.what();
    }
  }
  rep.payload_size = static_cast<int32_t>(rep.payload.size());
  ++served_;
  Bytes buf = encode_msg(rep);
  bus_.publish(rep_channel_, buf.data(), buf.size());
  remember(key, std::move(buf));
}

void RpcServer::remember(const std::string& key, Bytes reply) {
  remembered_bytes_ += reply.size();
  answered_[key] = std::move(reply);
  order_.push_back(key);
  // Bounded by count and by bytes: pages of a large world would otherwise keep megabytes
  // of replies that a retry within a call's timeout is the only use for.
  while (order_.size() > memory_ || (remembered_bytes_ > memory_bytes_ && order_.size() > 1)) {
    auto it = answered_.find(order_.front());
    remembered_bytes_ -= it->second.size();
    answered_.erase(it);
    order_.pop_front();
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
  it->second.done = true;
  it->second.status = rep.status;
  it->second.error = rep.error;
  it->second.payload.assign(rep.payload.begin(), rep.payload.end());
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
    bus_.publish(req_channel_, buf.data(), buf.size());
    if (attempts++ > 0) ++retries_;
    // Back off (x2 per attempt, to 1 s) so that a reply lost to an overrun receiver is
    // not followed by a flood of resent large replies.
    const auto backoff = std::min<std::chrono::milliseconds>(std::chrono::milliseconds(1000),
                                                             opts.retry_interval * (1 << std::min(attempts - 1, 10)));
    const auto resend_at = std::min(deadline, now + backoff);
    while (!done()) {
      const auto left = std::chrono::duration_cast<std::chrono::milliseconds>(resend_at - clock::now());
      if (left.count() <= 0) break;
      bus_.handle(left);
    }
  }
  Pending result = std::move(pending_[rid]);
  pending_.erase(rid);
  if (!result.done) {
    const double secs = std::chrono::duration<double>(opts.timeout).count();
    throw RpcTimeout("rpc " + area_ + "." + method + ": no reply on " + rpc_reply_channel(area_) + " within " +
                     std::to_string(secs).substr(0, 5) + " s (" + std::to_string(attempts) + " attempts)");
  }
  if (result.status != rpc_reply_t::OK) throw RpcRemoteError(result.status, result.error);
  return result.payload;
}

}  // namespace skillbus
