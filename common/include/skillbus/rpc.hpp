// RPC over the bus. A server of area "WM" takes rpc_request_t on SB_WM_REQ and answers
// with rpc_reply_t on SB_WM_REP; the payloads are LCM encodings of each method's own
// types. (client_id, request_id) names a call across retries:
//  * the client resends the same request every retry interval until a reply with its
//    ids arrives or the call's timeout passes (then RpcTimeout, never a hang);
//  * the server remembers the replies of the last `memory` calls and answers a retry
//    from that memory without running the method again, so a write happens once;
//  * failures come back as typed replies (ERROR, UNKNOWN_METHOD, BAD_REQUEST) that the
//    client raises as RpcRemoteError with the server's message;
//  * a reply larger than kRpcChunkBytes is sent in chunks of that size: the first with
//    the call's answer, the others when the client asks for them, a window at a time
//    (flow control: the client pulls no faster than it reads), each asked again if lost.
// Timeouts use the steady clock: they detect faults, they never steer behaviour.
#pragma once

#include <chrono>
#include <cstdint>
#include <functional>
#include <list>
#include <map>
#include <set>
#include <string>
#include <unordered_map>
#include <vector>

#include "skillbus/bus.hpp"
#include "skillbus/log.hpp"

namespace skillbus {

// The largest reply payload sent in one message: one UDP datagram of LCM, so that one
// lost datagram loses one chunk, which is asked for again, not the whole reply.
constexpr size_t kRpcChunkBytes = 48 * 1024;
// Chunks of a large reply a client asks for at a time.
constexpr int kRpcPullWindow = 16;
// The most chunks a client takes a reply in (768 MB): a reply that says more is refused
// (a garbled or forged count must not make it allocate without bound).
constexpr int32_t kRpcMaxChunks = 16384;

std::string rpc_request_channel(const std::string& area);  // "SB_<AREA>_REQ" (namespaced)
std::string rpc_reply_channel(const std::string& area);    // "SB_<AREA>_REP" (namespaced)

class RpcError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};
class RpcTimeout : public RpcError {
 public:
  using RpcError::RpcError;
};
class RpcRemoteError : public RpcError {
 public:
  RpcRemoteError(int8_t status, const std::string& what) : RpcError(what), status(status) {}
  int8_t status;
};
// Thrown by a method to answer BAD_REQUEST instead of ERROR.
class RpcBadRequest : public RpcError {
 public:
  using RpcError::RpcError;
};

// Thrown by a method that cannot answer yet: the server keeps the request unanswered and
// runs it again at retry_deferred() (a lockstep participant answers a query "as of frame
// n" only once it has finished its own frame n). A client's retries meanwhile are ignored.
class RpcDefer : public std::exception {
 public:
  const char* what() const noexcept override { return "deferred"; }
};

class RpcServer {
 public:
  using RawMethod = std::function<Bytes(const uint8_t* payload, size_t size)>;

  RpcServer(Bus& bus, const std::string& area, size_t memory = 4096, size_t memory_bytes = 64u << 20);
  ~RpcServer();

  void add_raw_method(const std::string& name, RawMethod method);

  // A method on generated LCM types: the request is decoded (BAD_REQUEST if it cannot
  // be) and the reply encoded. An exception thrown by fn becomes an ERROR reply.
  template <class Req, class Rep>
  void add_method(const std::string& name, std::function<Rep(const Req&)> fn) {
    add_raw_method(name, [name, fn](const uint8_t* p, size_t n) {
      Req req;
      if (!decode_msg(p, n, req)) throw RpcBadRequest("payload of " + name + " does not decode as its request type");
      return encode_msg(fn(req));
    });
  }

  // Runs the deferred requests again, oldest first (each may defer again).
  void retry_deferred();
  size_t deferred() const { return deferred_.size(); }

  long served() const { return served_; }
  long duplicates() const { return duplicates_; }
  long chunks_pulled() const { return pulled_; }
  long expired() const { return expired_; }
  const BadInputCounter& bad_input() const { return bad_; }

 private:
  // A method's answer: the reply without its payload, and the payload, sent in chunks.
  struct Answer {
    std::string client_id, method, error;
    int64_t request_id = 0;
    int8_t status = 0;
    Bytes payload;
    std::vector<bool> sent;  // a reply in chunks: which have been sent (a client may still be pulling)
    int32_t chunks() const;
    bool complete() const;   // every chunk sent at least once
  };
  void on_request(const std::string& ch, const uint8_t* data, size_t size);
  void send_chunk(Answer& a, int32_t chunk);
  void remember(const std::string& key, Answer answer);

  Bus& bus_;
  std::string area_, req_channel_, rep_channel_;
  size_t memory_, memory_bytes_;
  size_t remembered_bytes_ = 0;
  int sub_ = -1;
  std::map<std::string, RawMethod> methods_;
  std::list<std::string> order_;  // oldest first
  std::unordered_map<std::string, Answer> answered_;
  std::set<std::string> running_;  // calls whose method is running (a retry meanwhile waits for it)
  // Requests a method deferred, oldest first, by call key: (channel, request bytes).
  // Bounded: past kMaxDeferred the oldest is dropped, as if it had been lost.
  static constexpr size_t kMaxDeferred = 1024;
  std::list<std::pair<std::string, std::pair<std::string, Bytes>>> deferred_;
  long served_ = 0, duplicates_ = 0, expired_ = 0, pulled_ = 0;
  BadInputCounter bad_;
};

struct CallOptions {
  std::chrono::milliseconds timeout{2000};
  std::chrono::milliseconds retry_interval{100};
};

class RpcClient {
 public:
  // client_name is for people; the client id adds the pid and a per-incarnation nonce
  // so that a restarted client never collides with its predecessor's request ids.
  RpcClient(Bus& bus, const std::string& area, const std::string& client_name);
  ~RpcClient();

  Bytes call_raw(const std::string& method, const Bytes& payload, const CallOptions& opts = {});

  template <class Rep, class Req>
  Rep call(const std::string& method, const Req& req, const CallOptions& opts = {}) {
    const Bytes out = call_raw(method, encode_msg(req), opts);
    Rep rep;
    if (!decode_msg(out.data(), out.size(), rep))
      throw RpcError("reply of " + area_ + "." + method + " does not decode as its reply type");
    return rep;
  }

  const std::string& client_id() const { return client_id_; }
  long retries() const { return retries_; }
  // Called at least every 200 ms while a call waits for its reply: a caller that must be
  // heard while it waits (the skill manager's announcements, during an expansion that
  // plans for seconds) does it here.
  void set_while_waiting(std::function<void()> fn) { while_waiting_ = std::move(fn); }

 private:
  struct Pending {
    bool done = false;
    int8_t status = 0;
    std::string error;
    Bytes payload;
    std::vector<Bytes> parts;  // a reply in chunks: those received (empty: not yet)
    int32_t have = 0;
  };
  void on_reply(const std::string& ch, const uint8_t* data, size_t size);
  void wait(std::chrono::milliseconds left);  // the bus handled for at most `left`, then while_waiting_
  // Asks for the first kRpcPullWindow chunks of `p`'s reply still missing.
  void pull_missing(const std::string& method, int64_t request_id, int64_t deadline_ns, const Pending& p);

  Bus& bus_;
  std::string area_, req_channel_, client_id_;
  int sub_ = -1;
  int64_t next_request_id_ = 1;
  // By request id: a call made from a handler that runs while another call waits must
  // not take its reply.
  std::map<int64_t, Pending> pending_;
  long retries_ = 0;
  BadInputCounter bad_;
  std::function<void()> while_waiting_;
};

}  // namespace skillbus
