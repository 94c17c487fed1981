// sb_clock: a lockstep clock master without physics.
//
// Runs the lockstep protocol for the named participants and prints a one-line JSON
// summary on stdout (frames, sim time, wall time, real-time factor, digest, bad input).
// With --demo it also plays a toy world: it publishes SB_DEMO_STATE every frame and
// folds the participants' SB_DEMO_CMD messages (canonical order) into that state.
//
// Reads:   SB_LOCKSTEP_JOIN, SB_LOCKSTEP_ACK, SB_DEMO_CMD (with --demo)
// Writes:  SB_LOCKSTEP_CLOCK, SB_DEMO_STATE (with --demo)
// Role:    lockstep master. Exit code 0 when all frames ran, 1 on a lockstep error.
#include <cstdio>
#include <iostream>

#include "args.hpp"
#include "demo_mix.hpp"
#include "skillbus/bus.hpp"
#include "skillbus/faulty_bus.hpp"
#include "skillbus/lockstep.hpp"
#include "skillbus_msgs/test_sample_t.hpp"

using namespace skillbus;

namespace {


}  // namespace

int main(int argc, char** argv) {
  apps::Args args(argc, argv,
                  {"url", "name", "participants", "frames", "period-ms", "join-timeout-ms", "ack-timeout-ms",
                   "message-timeout-ms", "lose-clocks-every"},
                  {"demo"});
  MasterConfig cfg;
  cfg.name = args.str("name", "clock");
  cfg.participants = args.list("participants");
  cfg.frames = args.num("frames", 1000);
  cfg.frame_period_ns = static_cast<int64_t>(args.real("period-ms", 10.0) * 1e6);
  cfg.join_timeout = std::chrono::milliseconds(args.num("join-timeout-ms", 10000));
  cfg.ack_timeout = std::chrono::milliseconds(args.num("ack-timeout-ms", 5000));
  cfg.message_timeout = std::chrono::milliseconds(args.num("message-timeout-ms", 2000));
  if (cfg.frame_period_ns <= 0) apps::Args::die("--period-ms must be positive");

  std::unique_ptr<Bus> bus;
  try {
    // --lose-clocks-every N: a test of the clock resend (every N-th clock is lost).
    bus = std::make_unique<DropEveryNthBus>(open_bus(args.str("url")),
                                            static_cast<int>(args.num("lose-clocks-every", 0)), clock_channel());
  } catch (const std::exception& e) {
    apps::Args::die(e.what());
  }
  LockstepMaster master(*bus, cfg);

  uint64_t world = 0;
  long commands = 0;
  if (args.flag("demo")) {
    master.subscribe(channel("SB_DEMO_CMD"), [&](const StampedMessage& m) {
      skillbus_msgs::test_sample_t cmd;
      if (!decode_msg(m.data.data(), m.data.size(), cmd))
        throw std::runtime_error(m.channel + " from " + m.stamp.sender + " is not a test_sample_t");
      world = apps::demo_mix(world, cmd.i64);
      ++commands;
    });
    master.on_frame_start = [&](int64_t frame, int64_t sim_time) {
      skillbus_msgs::test_sample_t state{};
      state.i64 = static_cast<int64_t>(world);
      state.f64 = static_cast<double>(sim_time) * 1e-9;
      state.text = "world";
      master.publish(channel("SB_DEMO_STATE"), state);
    };
  }

  const RunResult r = master.run();
  const double rtf = r.wall_seconds > 0 ? (r.sim_time_ns * 1e-9) / r.wall_seconds : 0.0;
  std::printf(
      "{\"ok\": %s, \"error\": \"%s\", \"frames\": %lld, \"participants\": %zu, \"sim_time_s\": %.3f, "
      "\"wall_time_s\": %.3f, \"real_time_factor\": %.2f, \"us_per_frame\": %.1f, \"digest\": \"%s\", "
      "\"commands\": %ld, \"bad_input\": %ld}\n",
      r.ok ? "true" : "false", apps::json_escape(r.error).c_str(), static_cast<long long>(r.frames), cfg.participants.size(),
      r.sim_time_ns * 1e-9, r.wall_seconds, rtf, r.frames ? r.wall_seconds * 1e6 / r.frames : 0.0,
      r.digest_hex().c_str(), commands, master.bad_input().total());
  std::fflush(stdout);
  return r.ok ? 0 : 1;
}
