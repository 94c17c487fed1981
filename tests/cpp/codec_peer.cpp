// codec_peer: the C++ half of the cross-language codec test (tests/integration/test_codec.py).
//   --publish SECONDS  publish the canonical sample of every type on SB_CODEC_C2P_<type>
//                      every 20 ms for that long
//   --check SECONDS    receive every type on SB_CODEC_P2C_<type> (published by Python),
//                      decode it, re-encode it, and compare with the canonical sample;
//                      print one JSON line {type: "ok" | why} and exit 0 if all are ok
// The canonical samples are built field by field here and in codec_samples.py.
#include <cstdio>
#include <map>
#include <thread>

#include "skillbus/bus.hpp"
#include "skillbus_msgs/channel_count_t.hpp"
#include "skillbus_msgs/header_t.hpp"
#include "skillbus_msgs/lockstep_ack_t.hpp"
#include "skillbus_msgs/lockstep_clock_t.hpp"
#include "skillbus_msgs/lockstep_join_t.hpp"
#include "skillbus_msgs/rpc_counter_t.hpp"
#include "skillbus_msgs/rpc_reply_t.hpp"
#include "skillbus_msgs/rpc_request_t.hpp"
#include "skillbus_msgs/test_sample_t.hpp"

using namespace skillbus;
using namespace skillbus_msgs;

namespace {

header_t header(int64_t frame, const std::string& sender, int32_t seq) {
  header_t h{};
  h.frame = frame;
  h.sim_time_ns = frame * 10'000'000;
  h.sender = sender;
  h.seq = seq;
  return h;
}

channel_count_t count(const std::string& s, const std::string& ch, int64_t frame, int32_t n) {
  channel_count_t c{};
  c.sender = s;
  c.channel = ch;
  c.frame = frame;
  c.count = n;
  return c;
}

template <class T>
bool roundtrip_equal(const uint8_t* d, size_t n, const Bytes& canonical, std::string& why) {
  T m;
  if (!decode_msg(d, n, m)) return (why = "does not decode"), false;
  if (encode_msg(m) != canonical) return (why = "decoded and re-encoded differs from the canonical sample"), false;
  return true;
}

struct Sample {
  Bytes bytes;
  std::function<bool(const uint8_t*, size_t, std::string&)> check;
};

template <class T>
Sample sample(const T& m) {
  Bytes b = encode_msg(m);
  return {b, [b](const uint8_t* d, size_t n, std::string& why) { return roundtrip_equal<T>(d, n, b, why); }};
}

std::map<std::string, Sample> samples() {
  std::map<std::string, Sample> s;
  test_sample_t t{};
  t.header = header(7, "codec", 3);
  t.i8 = -8;
  t.i16 = -1600;
  t.i32 = -320000;
  t.i64 = -64000000000LL;
  t.f32 = 1.5f;
  t.f64 = -2.25;
  t.flag = true;
  t.text = "h\xc3\xa9llo w\xc3\xb6rld";
  t.fixed[0] = 1.0;
  t.fixed[1] = 2.0;
  t.fixed[2] = 3.0;
  t.values = {1, -2, 3000000000LL};
  t.num_values = 3;
  t.names = {"a", "", "ccc"};
  t.num_names = 3;
  t.items = {count("s1", "SB_A", 1, 2), count("s2", "SB_B", 3, 4)};
  t.num_items = 2;
  t.rows = 2;
  t.cols = 3;
  t.matrix = {{1, 2, 3}, {4, 5, 6}};
  const uint8_t blob[4] = {0, 1, 254, 255};
  std::copy(blob, blob + 4, t.blob);
  s["test_sample_t"] = sample(t);

  lockstep_clock_t c{};
  c.header = header(5, "clock", 0);
  c.frame_period_ns = 10'000'000;
  c.participants = {"a", "b"};
  c.num_participants = 2;
  c.counts = {count("a", "SB_A", 4, 1), count("b", "SB_B", 4, 2)};
  c.num_counts = 2;
  c.stop = true;
  c.stop_reason = "because";
  s["lockstep_clock_t"] = sample(c);

  lockstep_ack_t a{};
  a.header = header(5, "a", 0);
  a.counts = {count("a", "SB_A", 5, 1)};
  a.num_counts = 1;
  for (int i = 0; i < 32; ++i) a.digest[i] = static_cast<uint8_t>(i);
  a.error = "oops";
  s["lockstep_ack_t"] = sample(a);

  lockstep_join_t j{};
  j.participant = "p1";
  j.kind = "python";
  j.pid = 1234;
  s["lockstep_join_t"] = sample(j);

  rpc_request_t q{};
  q.client_id = "c:1:ab";
  q.request_id = 42;
  q.deadline_ns = 123456789;
  q.method = "add";
  q.payload = {1, 2, 3, 0, 255};
  q.payload_size = 5;
  s["rpc_request_t"] = sample(q);

  rpc_reply_t r{};
  r.client_id = "c:1:ab";
  r.request_id = 42;
  r.method = "add";
  r.status = rpc_reply_t::ERROR;
  r.error = "bad";
  r.payload = {9, 8};
  r.payload_size = 2;
  s["rpc_reply_t"] = sample(r);

  rpc_counter_t k{};
  k.key = "k";
  k.amount = 5;
  k.value = 10;
  k.writes = 2;
  s["rpc_counter_t"] = sample(k);

  s["channel_count_t"] = sample(count("s", "SB_X", 9, 3));
  s["header_t"] = sample(header(1, "h", 4));
  return s;
}

}  // namespace

int main(int argc, char** argv) {
  if (argc != 3) {
    std::fprintf(stderr, "usage: codec_peer --publish SECONDS | --check SECONDS\n");
    return 2;
  }
  const std::string mode = argv[1];
  const auto duration = std::chrono::milliseconds(static_cast<long>(std::atof(argv[2]) * 1000));
  auto bus = open_bus();
  auto all = samples();
  const auto end = std::chrono::steady_clock::now() + duration;
  if (mode == "--publish") {
    while (std::chrono::steady_clock::now() < end) {
      for (const auto& [name, s] : all) bus->publish("SB_CODEC_C2P_" + name, s.bytes.data(), s.bytes.size());
      std::this_thread::sleep_for(std::chrono::milliseconds(20));
    }
    return 0;
  }
  std::map<std::string, std::string> verdict;
  for (auto& [name, s] : all) {
    const std::string type = name;
    auto check = s.check;
    bus->subscribe("SB_CODEC_P2C_" + type, [&verdict, type, check](const std::string&, const uint8_t* d, size_t n) {
      if (verdict.count(type)) return;
      std::string why;
      verdict[type] = check(d, n, why) ? "ok" : why;
    });
  }
  while (verdict.size() < all.size() && std::chrono::steady_clock::now() < end) bus->handle(std::chrono::milliseconds(20));
  bool ok = verdict.size() == all.size();
  std::string json = "{";
  for (const auto& [name, s] : all) {
    auto it = verdict.find(name);
    const std::string v = it == verdict.end() ? "never received" : it->second;
    ok = ok && v == "ok";
    json += (json.size() > 1 ? ", " : "") + std::string("\"") + name + "\": \"" + v + "\"";
  }
  std::printf("%s}\n", json.c_str());
  return ok ? 0 : 1;
}
