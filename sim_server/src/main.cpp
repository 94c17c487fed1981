// sim_server: the DART physics server. See sim_server/README.md.
#include <cstdio>
#include <string>
#include <vector>

#include "skillbus/apps/cli.hpp"
#include "skillbus/apps/cpu_latency.hpp"
#include "skillbus/apps/lifecycle.hpp"
#include "skillbus/apps/summary.hpp"
#include "skillbus/auth.hpp"
#include "skillbus/sim/server.hpp"
#include "libraries_in_use.hpp"

using namespace skillbus;

int main(int argc, char** argv) {
  CLI::App app{"The DART physics server: plays the robot and the objects of a scene file, serves the robot "
               "interface and the SIM services, and is the lockstep clock master (or runs on the wall clock). "
               "Prints a one-line JSON summary when it ends.",
               "sim_server"};
  apps::configure(app);
  std::string url;
  sim::ServerOptions o;
  int64_t join_ms = 10000, ack_ms = 5000, message_ms = 2000, ack_poll_us = 0, cpu_latency_us = -1;
  apps::add_url_option(app, url);
  app.add_option("--scene", o.scene_file, "the scene file (required; e.g. deploy/scenes/demo.scene.json)")->type_name("FILE");
  app.add_option("--scenes", o.scenes_dir,
                 "the folder SIM.load_scene takes scene names from (default: the --scene file's folder)")
      ->type_name("DIR");
  app.add_option("--script", o.script_file, "play this command script in-process (no participant needed)")->type_name("FILE");
  app.add_option("--record-script", o.record_script, "write every accepted command to this file, as a script")->type_name("FILE");
  app.add_option("--name", o.name, "its name on the bus");
  apps::add_list_option(app, "--participants", o.participants, "lockstep: who must join and ack every frame");
  apps::add_list_option(app, "--end-when-asked-by", o.end_when_asked_by,
                        "lockstep: end a session asked to end only once each of these participants has asked "
                        "(default: when the first asks)");
  app.add_flag("--wall-clock", o.wall_clock, "run on the wall clock instead of as lockstep master");
  app.add_option("--speed", o.speed, "wall clock: sim seconds per wall second")->check(apps::positive());
  app.add_option("--frames", o.frames, "frames to run (-1: until stopped)");
  app.add_option("--duration-s", o.duration_s, "sim time to run (> 0: overrides --frames)");
  app.add_flag("--pipeline", o.pipeline,
               "lockstep: step the physics while the participants work (commands take effect a frame later)");
  app.add_option("--collision", o.collision_detector, "collision detector bullet, dart or fcl (empty: the scene's)");
  app.add_option("--step-ms", o.step_ms, "physics step, ms (0: the scene's)");
  app.add_option("--frame-ms", o.frame_ms, "frame, ms (0: the scene's)");
  app.add_option("--join-timeout-ms", join_ms, "lockstep: how long to wait for every participant to join");
  app.add_option("--ack-timeout-ms", ack_ms, "lockstep: how long to wait for a frame's acks");
  std::vector<std::string> ack_of;
  apps::add_ack_timeouts_option(app, ack_of);
  app.add_option("--message-timeout-ms", message_ms, "lockstep: how long to wait for an announced message");
  apps::add_ack_poll_option(app, ack_poll_us);
  apps::add_cpu_latency_option(app, cpu_latency_us);
  apps::parse_or_exit(app, argc, argv);
  if (o.scene_file.empty()) apps::usage_error(app, "--scene FILE is required (e.g. deploy/scenes/demo.scene.json)");
  // An option of the other mode would be ignored without a word: refused, naming it.
  for (const char* lockstep_only : {"--participants", "--end-when-asked-by", "--pipeline", "--join-timeout-ms",
                                    "--ack-timeout-ms", "--ack-timeout-ms-of", "--message-timeout-ms", "--ack-poll-us"})
    if (o.wall_clock && app.count(lockstep_only) > 0)
      apps::usage_error(app, std::string(lockstep_only) + " is for lockstep: not with --wall-clock");
  if (!o.wall_clock && app.count("--speed") > 0)
    apps::usage_error(app, "--speed is for the wall clock: it needs --wall-clock (under lockstep the frames set the pace)");
  o.join_timeout = std::chrono::milliseconds(join_ms);
  o.ack_timeout = std::chrono::milliseconds(ack_ms);
  o.ack_timeout_of = apps::parse_ack_timeouts(app, ack_of);
  o.message_timeout = std::chrono::milliseconds(message_ms);
  o.ack_poll = std::chrono::microseconds(ack_poll_us);

  const auto cpu_latency = apps::hold_cpu_latency_or_exit("sim_server", cpu_latency_us);
  std::unique_ptr<Bus> bus;
  std::unique_ptr<sim::SimServer> server;
  apps::start_or_exit("sim_server", [&] {
    bus = open_bus(url);
    server = std::make_unique<sim::SimServer>(*bus, o);
  });
  apps::stop_on_signals();
  const sim::ServerReport rep = server->run_until([] { return apps::stop_requested() != 0; });
  const auto& r = rep.run;
  // Where each object ended (x y z in the world), for people and for the demo's summary.
  skillbus_msgs::sim_state_t state{};
  server->physics().fill_state(0, state);
  apps::Summary objects = apps::Summary::object();
  for (const auto& ob : state.objects)
    objects[ob.name] = {apps::rounded(ob.pose[0], 4), apps::rounded(ob.pose[1], 4), apps::rounded(ob.pose[2], 4)};
  // Where a frame's wall time went, in ms per frame: publishing the state, the physics
  // (and commands), the wait for the participants' acks (the slowest of each frame), each
  // participant's clock-to-ack time as the master read it (no ack is read during the
  // physics' step: one that came then counts until the step's end), and how long each
  // participant's ack came after the step (held_: what it added to the frame), with the
  // share of frames its ack was the last one of (ended_by).
  const double f = r.frames > 0 ? static_cast<double>(r.frames) : 1.0;
  apps::Summary frame_ms;
  frame_ms["state"] = apps::rounded(rep.frame_start_seconds * 1e3 / f, 3);
  frame_ms["physics"] = apps::rounded(rep.frame_end_seconds * 1e3 / f, 3);
  frame_ms["ack_wait"] = apps::rounded(rep.ack_wait_seconds * 1e3 / f, 3);
  frame_ms["total"] = apps::rounded(r.wall_seconds * 1e3 / f, 3);
  for (const auto& [name, s] : rep.ack_seconds) frame_ms["ack_" + name] = apps::rounded(s * 1e3 / f, 3);
  for (const auto& [name, s] : rep.held_seconds) frame_ms["held_" + name] = apps::rounded(s * 1e3 / f, 3);
  apps::Summary ended_by = apps::Summary::object();
  for (const auto& [name, n] : rep.ended_by) ended_by[name] = apps::rounded(static_cast<double>(n) / f, 3);
  const double rtf = r.wall_seconds > 0 ? r.sim_time_ns * 1e-9 / r.wall_seconds : 0.0;

  apps::Summary out;
  out["ok"] = r.ok;
  out["error"] = r.error;
  out["frames"] = r.frames;
  out["sim_time_s"] = apps::rounded(r.sim_time_ns * 1e-9, 3);
  out["wall_time_s"] = apps::rounded(r.wall_seconds, 3);
  out["real_time_factor"] = apps::rounded(rtf, 2);
  out["steps"] = rep.steps;
  out["physics_us_per_step"] = apps::rounded(rep.steps ? rep.physics_seconds * 1e6 / rep.steps : 0.0, 1);
  out["collision_detector"] = server->physics().collision_detector();
  out["allocator"] = sim::allocator_in_use();
  out["dart"] = sim::dart_in_use();
  out["participants"] = o.participants.size();
  out["state_digest"] = to_hex(rep.state_digest);
  out["session_digest"] = r.digest_hex();
  out["commands_accepted"] = rep.accepted;
  out["commands_rejected"] = rep.rejected;
  out["bad_input"] = rep.bad_input;
  if (const auto in_force = cpu_latency ? cpu_latency->in_force_us() : std::nullopt)
    out["cpu_latency_us"] = *in_force;  // what the kernel applied at the end (docs/lockstep.md)
  out["finger_width"] = apps::rounded(state.finger_width, 5);  // (the first robot's)
  out["finger_force"] = apps::rounded(state.finger_force, 3);
  if (server->physics().num_robots() > 1) {
    apps::Summary robots = apps::Summary::array();
    for (const auto& rb : server->physics().scene().robots) robots.push_back(rb.name);
    out["robots"] = robots;
    out["robot_contact_steps"] = server->physics().robot_contact_steps();  // steps in which two robots touched
  }
  if (const auto steps = server->physics().obstacle_contact_steps(); !steps.empty()) {
    apps::Summary by_name = apps::Summary::object();
    for (const auto& [name, n] : steps) by_name[name] = n;
    out["obstacle_contact_steps"] = by_name;  // steps in which a robot touched each obstacle
  }
  out["objects"] = objects;
  out["frame_ms"] = frame_ms;
  out["frames_ended_by"] = ended_by;  // the share of frames whose last ack was each participant's
  // Messages the bus refused (no key, a wrong key, replayed, stale, not this sender's channel).
  if (const auto* a = auth::stats_of(*bus)) out["bus_rejected"] = a->rejected;
  apps::print_summary(out);
  return r.ok ? 0 : 1;
}
