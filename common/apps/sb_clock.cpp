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
#include <algorithm>
#include <cstdio>
#include <iostream>

#include "demo_mix.hpp"
#include "skillbus/apps/cli.hpp"
#include "skillbus/apps/cpu_latency.hpp"
#include "skillbus/apps/lifecycle.hpp"
#include "skillbus/apps/summary.hpp"
#include "skillbus/auth.hpp"
#include "skillbus/bus.hpp"
#include "skillbus/faulty_bus.hpp"
#include "skillbus/lockstep.hpp"
#include "skillbus_msgs/test_sample_t.hpp"

using namespace skillbus;

int main(int argc, char** argv) {
  CLI::App app{"A lockstep clock master without physics: runs the lockstep protocol for the named participants "
               "and prints a one-line JSON summary.",
               "sb_clock"};
  apps::configure(app);
  std::string url;
  MasterConfig cfg;
  cfg.name = "clock";
  int64_t frames = 1000, join_ms = 10000, ack_ms = 5000, message_ms = 2000, ack_poll_us = 0, cpu_latency_us = -1;
  double period_ms = 10.0;
  int lose_clocks_every = 0;
  bool demo = false;
  apps::add_url_option(app, url);
  app.add_option("--name", cfg.name, "its name on the bus");
  apps::add_list_option(app, "--participants", cfg.participants, "the participants that must join and ack every frame");
  app.add_option("--frames", frames, "frames to run");
  app.add_option("--period-ms", period_ms, "sim time per frame, ms")->check(apps::positive());
  app.add_option("--join-timeout-ms", join_ms, "how long to wait for every participant to join");
  app.add_option("--ack-timeout-ms", ack_ms, "how long to wait for a frame's acks");
  std::vector<std::string> ack_of;
  apps::add_ack_timeouts_option(app, ack_of);
  app.add_option("--message-timeout-ms", message_ms, "how long to wait for an announced message");
  apps::add_ack_poll_option(app, ack_poll_us);
  apps::add_cpu_latency_option(app, cpu_latency_us);
  app.add_option("--lose-clocks-every", lose_clocks_every, "tests: lose every N-th clock message (0: none)");
  app.add_flag("--demo", demo, "play the toy world: publish SB_DEMO_STATE, fold in SB_DEMO_CMD");
  apps::parse_or_exit(app, argc, argv);
  cfg.frames = frames;
  cfg.frame_period_ns = static_cast<int64_t>(period_ms * 1e6);
  cfg.join_timeout = std::chrono::milliseconds(join_ms);
  cfg.ack_timeout = std::chrono::milliseconds(ack_ms);
  cfg.ack_timeout_of = apps::parse_ack_timeouts(app, ack_of);
  for (const auto& [name, ms] : cfg.ack_timeout_of)
    if (std::find(cfg.participants.begin(), cfg.participants.end(), name) == cfg.participants.end())
      apps::usage_error(app, "--ack-timeout-ms-of names '" + name + "', who is not among --participants");
  cfg.message_timeout = std::chrono::milliseconds(message_ms);
  cfg.ack_poll = std::chrono::microseconds(ack_poll_us);
  if (cfg.frame_period_ns <= 0) apps::usage_error(app, "--period-ms must be positive");

  const auto cpu_latency = apps::hold_cpu_latency_or_exit("sb_clock", cpu_latency_us);
  std::unique_ptr<Bus> bus;
  const Bus* opened = nullptr;  // (the bus under the test's wrapper: its refusals for the summary)
  apps::start_or_exit("sb_clock", [&] {
    // --lose-clocks-every N: a test of the clock resend (every N-th clock is lost).
    auto inner = open_bus(url);
    opened = inner.get();
    bus = std::make_unique<DropEveryNthBus>(std::move(inner), lose_clocks_every, clock_channel());
  });
  LockstepMaster master(*bus, cfg);

  uint64_t world = 0;
  long commands = 0;
  if (demo) {
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
  apps::Summary out;
  out["ok"] = r.ok;
  out["error"] = r.error;
  out["frames"] = r.frames;
  out["participants"] = cfg.participants.size();
  out["sim_time_s"] = apps::rounded(r.sim_time_ns * 1e-9, 3);
  out["wall_time_s"] = apps::rounded(r.wall_seconds, 3);
  out["real_time_factor"] = apps::rounded(rtf, 2);
  out["us_per_frame"] = apps::rounded(r.frames ? r.wall_seconds * 1e6 / r.frames : 0.0, 1);
  out["digest"] = r.digest_hex();
  out["commands"] = commands;
  out["bad_input"] = master.bad_input().total();
  if (const auto* a = auth::stats_of(*opened)) out["bus_rejected"] = a->rejected;  // (unsigned, bad_mac, ...)
  if (const auto in_force = cpu_latency ? cpu_latency->in_force_us() : std::nullopt)
    out["cpu_latency_us"] = *in_force;  // what the kernel applied at the end (docs/lockstep.md)
  // Per participant: the ms its acks kept the master waiting after the clock went out (an
  // ack already in when the master first read the bus counts nothing), summed over the
  // run, and the frames its ack was the last one of (LockstepMaster::held_seconds).
  apps::Summary held = apps::Summary::object(), ended_by = apps::Summary::object();
  for (const auto& [name, s] : master.held_seconds()) held[name] = apps::rounded(s * 1e3, 3);
  for (const auto& [name, n] : master.ended_by()) ended_by[name] = n;
  out["held_ms"] = held;
  out["frames_ended_by"] = ended_by;
  apps::print_summary(out);
  return r.ok ? 0 : 1;
}
