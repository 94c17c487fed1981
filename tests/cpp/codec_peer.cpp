// codec_peer: the C++ half of the cross-language codec test (tests/integration/test_codec.py).
//   --publish SECONDS  publish the canonical sample of every type on SB_CODEC_C2P_<type>
//                      every 20 ms for that long
//   --check SECONDS    receive every type on SB_CODEC_P2C_<type> (published by Python),
//                      decode it, re-encode it, and compare with the canonical sample;
//                      print one JSON line {type: "ok" | why} and exit 0 if all are ok
// The canonical sample of every type is built field by field by codec_samples.hpp, which
// tests/integration/codec_samples.py generates at build time from the bindings of
// lcmtypes/ (its Python half builds the same values).
#include <cstdio>
#include <cstdlib>
#include <functional>
#include <map>
#include <thread>

#include "codec_samples.hpp"
#include "skillbus/bus.hpp"

using namespace skillbus;

namespace {

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
  codec_samples::for_each_sample([&s](const char* name, const auto& m) { s[name] = sample(m); });
  return s;
}

}  // namespace

int main(int argc, char** argv) {
  if (argc != 3) {
    std::fprintf(stderr, "usage: codec_peer --publish SECONDS | --check SECONDS | --echo SECONDS\n");
    return 2;
  }
  const std::string mode = argv[1];
  const auto duration = std::chrono::milliseconds(static_cast<long>(std::atof(argv[2]) * 1000));
  auto bus = open_bus();
  auto all = samples();
  const auto end = std::chrono::steady_clock::now() + duration;
  if (mode == "--echo") {
    // Every message on SB_ECHO_IN back on SB_ECHO_OUT, bytes unchanged: what the bus
    // received (reassembled from LCM's fragments when large) and what it publishes.
    long echoed = 0;
    bus->subscribe("SB_ECHO_IN", [&](const std::string&, const uint8_t* d, size_t n) {
      bus->publish("SB_ECHO_OUT", d, n);
      ++echoed;
    });
    std::printf("ready\n");
    std::fflush(stdout);
    while (std::chrono::steady_clock::now() < end) bus->handle(std::chrono::milliseconds(20));
    std::printf("{\"echoed\": %ld}\n", echoed);
    return 0;
  }
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
