// sb_demo_participant: a C++ lockstep participant of the demo world (see sb_clock --demo).
//
// Each frame it folds SB_DEMO_STATE and the other participants' SB_DEMO_CMD (canonical
// order) into its state and publishes SB_DEMO_CMD with the result. Prints a JSON summary.
// --drop-at-frame N announces but does not send its SB_DEMO_CMD of frame N (to test that
// a lost message is reported with its channel and frame). --bare: no demo traffic.
// --slow-at-frame N spends 0.8 s in frame N dispatching the bus (a slow participant).
//
// Reads:   SB_LOCKSTEP_CLOCK, SB_DEMO_STATE, SB_DEMO_CMD
// Writes:  SB_LOCKSTEP_JOIN, SB_LOCKSTEP_ACK, SB_DEMO_CMD
// Role:    lockstep participant (or wall-clock with --wall-clock).
#include <cstdio>

#include "args.hpp"
#include "demo_mix.hpp"
#include "skillbus/bus.hpp"
#include "skillbus/lockstep.hpp"
#include "skillbus_msgs/test_sample_t.hpp"

using namespace skillbus;

namespace {

// Drops the next publish on one channel when armed: the sender still counts it.
class DropNextBus : public Bus {
 public:
  explicit DropNextBus(std::unique_ptr<Bus> inner) : inner_(std::move(inner)) {}
  void publish(const std::string& ch, const void* d, size_t n) override {
    if (armed_ && ch == channel_) { armed_ = false; return; }
    inner_->publish(ch, d, n);
  }
  int subscribe(const std::string& ch, Handler h, int cap = 10000) override { return inner_->subscribe(ch, std::move(h), cap); }
  void unsubscribe(int id) override { inner_->unsubscribe(id); }
  bool handle(std::chrono::milliseconds t) override { return inner_->handle(t); }
  std::string url() const override { return inner_->url(); }
  void arm(const std::string& ch) { armed_ = true; channel_ = ch; }

 private:
  std::unique_ptr<Bus> inner_;
  bool armed_ = false;
  std::string channel_;
};

}  // namespace

int main(int argc, char** argv) {
  apps::Args args(argc, argv, {"url", "name", "drop-at-frame", "slow-at-frame", "clock-timeout-ms", "message-timeout-ms", "frames"},
                  {"wall-clock", "bare"});
  ParticipantConfig cfg;
  cfg.name = args.str("name");
  if (cfg.name.empty()) apps::Args::die("--name is required");
  cfg.kind = "cpp-demo";
  cfg.mode = args.flag("wall-clock") ? ClockMode::WallClock : ClockMode::Lockstep;
  cfg.wall_frames = args.num("frames", -1);
  cfg.clock_timeout = std::chrono::milliseconds(args.num("clock-timeout-ms", 10000));
  cfg.message_timeout = std::chrono::milliseconds(args.num("message-timeout-ms", 2000));
  const long long drop_at = args.num("drop-at-frame", -1);
  const long long slow_at = args.num("slow-at-frame", -1);

  std::unique_ptr<DropNextBus> bus;
  try {
    bus = std::make_unique<DropNextBus>(open_bus(args.str("url")));
  } catch (const std::exception& e) {
    apps::Args::die(e.what());
  }
  LockstepParticipant p(*bus, cfg);
  const std::string cmd_channel = channel("SB_DEMO_CMD");
  uint64_t state = 0;
  long received = 0;
  auto fold = [&](const StampedMessage& m) {
    skillbus_msgs::test_sample_t s;
    if (!decode_msg(m.data.data(), m.data.size(), s))  // it passed the lockstep checks: a sender is broken
      throw std::runtime_error(m.channel + " from " + m.stamp.sender + " in frame " + std::to_string(m.stamp.frame) +
                               " is not a test_sample_t");
    state = apps::demo_mix(state, s.i64);
    ++received;
  };
  if (!args.flag("bare")) {  // --bare: only the lockstep protocol (benchmarks)
    p.subscribe(channel("SB_DEMO_STATE"), fold);
    p.subscribe(cmd_channel, fold);
  }
  p.on_frame = [&](int64_t frame, int64_t sim_time) {
    if (args.flag("bare")) return;
    if (frame == slow_at) {
      // Test: a slow frame, longer than the master's clock resend interval, spent
      // dispatching the bus as a long synchronous RPC call would.
      const auto end = std::chrono::steady_clock::now() + std::chrono::milliseconds(800);
      while (std::chrono::steady_clock::now() < end) bus->handle(std::chrono::milliseconds(50));
    }
    skillbus_msgs::test_sample_t out{};
    out.i64 = static_cast<int64_t>(apps::demo_mix(state, frame));
    out.text = cfg.name;
    if (frame == drop_at) bus->arm(cmd_channel);
    p.publish(cmd_channel, out);
  };
  const RunResult r = p.run();
  std::printf("{\"ok\": %s, \"name\": \"%s\", \"frames\": %lld, \"received\": %ld, \"digest\": \"%s\", \"bad_input\": %ld}\n",
              r.ok ? "true" : "false", cfg.name.c_str(), static_cast<long long>(r.frames), received,
              r.digest_hex().c_str(), p.bad_input().total());
  std::fflush(stdout);
  return r.ok ? 0 : 1;
}
