// sb_demo_participant: a C++ lockstep participant of the demo world (see sb_clock --demo).
//
// Each frame it folds SB_DEMO_STATE and the other participants' SB_DEMO_CMD (canonical
// order) into its state and publishes SB_DEMO_CMD with the result. Prints a JSON summary.
// --drop-at-frame N announces but does not send its SB_DEMO_CMD of frame N (to test that
// a lost message is reported with its channel and frame). --bare: no demo traffic.
// --slow-at-frame N spends --slow-ms (0.8 s) in frame N dispatching the bus (a slow participant).
//
// Reads:   SB_LOCKSTEP_CLOCK, SB_DEMO_STATE, SB_DEMO_CMD
// Writes:  SB_LOCKSTEP_JOIN, SB_LOCKSTEP_ACK, SB_DEMO_CMD
// Role:    lockstep participant (or wall-clock with --wall-clock).
#include <cstdio>

#include "demo_mix.hpp"
#include "skillbus/apps/cli.hpp"
#include "skillbus/apps/lifecycle.hpp"
#include "skillbus/apps/summary.hpp"
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
  std::chrono::steady_clock::time_point caught_up_at() const override { return inner_->caught_up_at(); }
  void arm(const std::string& ch) { armed_ = true; channel_ = ch; }

 private:
  std::unique_ptr<Bus> inner_;
  bool armed_ = false;
  std::string channel_;
};

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{"A C++ lockstep participant of the demo world (see sb_clock --demo): folds what it receives into "
               "its state and publishes SB_DEMO_CMD every frame; prints a one-line JSON summary.",
               "sb_demo_participant"};
  apps::configure(app);
  std::string url;
  ParticipantConfig cfg;
  bool wall_clock = false, bare = false;
  int64_t frames = -1, clock_ms = 10000, message_ms = 2000, drop_at = -1, slow_at = -1, slow_ms = 800;
  apps::add_url_option(app, url);
  app.add_option("--name", cfg.name, "its participant name (required)");
  app.add_flag("--wall-clock", wall_clock, "run on the wall clock instead of in lockstep");
  app.add_option("--frames", frames, "with --wall-clock: frames to run (-1: until stopped)");
  app.add_option("--clock-timeout-ms", clock_ms, "how long to wait for the next clock message");
  app.add_option("--message-timeout-ms", message_ms, "how long to wait for an announced message");
  app.add_option("--drop-at-frame", drop_at, "tests: announce but do not send its SB_DEMO_CMD of this frame");
  app.add_option("--slow-at-frame", slow_at, "tests: spend --slow-ms dispatching the bus in this frame");
  app.add_option("--slow-ms", slow_ms, "tests: how long the slow frame takes (ms)")->check(apps::positive());
  app.add_flag("--bare", bare, "only the lockstep protocol, no demo traffic (benchmarks)");
  apps::parse_or_exit(app, argc, argv);
  if (cfg.name.empty()) apps::usage_error(app, "--name is required");
  cfg.kind = "cpp-demo";
  cfg.mode = wall_clock ? ClockMode::WallClock : ClockMode::Lockstep;
  cfg.wall_frames = frames;
  cfg.clock_timeout = std::chrono::milliseconds(clock_ms);
  cfg.message_timeout = std::chrono::milliseconds(message_ms);

  std::unique_ptr<DropNextBus> bus;
  apps::start_or_exit("sb_demo_participant", [&] { bus = std::make_unique<DropNextBus>(open_bus(url)); });
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
  if (!bare) {  // --bare: only the lockstep protocol (benchmarks)
    p.subscribe(channel("SB_DEMO_STATE"), fold);
    p.subscribe(cmd_channel, fold);
  }
  p.on_frame = [&](int64_t frame, int64_t sim_time) {
    if (bare) return;
    if (frame == slow_at) {
      // Test: a slow frame, longer than the master's clock resend interval, spent
      // dispatching the bus as a long synchronous RPC call would.
      const auto end = std::chrono::steady_clock::now() + std::chrono::milliseconds(slow_ms);
      while (std::chrono::steady_clock::now() < end) bus->handle(std::chrono::milliseconds(50));
    }
    skillbus_msgs::test_sample_t out{};
    out.i64 = static_cast<int64_t>(apps::demo_mix(state, frame));
    out.text = cfg.name;
    if (frame == drop_at) bus->arm(cmd_channel);
    p.publish(cmd_channel, out);
  };
  const RunResult r = p.run();
  apps::Summary out;
  out["ok"] = r.ok;
  out["error"] = r.error;
  out["name"] = cfg.name;
  out["frames"] = r.frames;
  out["received"] = received;
  out["digest"] = r.digest_hex();
  out["bad_input"] = p.bad_input().total();
  apps::print_summary(out);
  return r.ok ? 0 : 1;
}
