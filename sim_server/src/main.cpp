// sim_server: the DART physics server. See sim_server/README.md.
#include <cstdio>

#include "../../common/apps/args.hpp"
#include "server.hpp"

using namespace skillbus;

namespace {

}  // namespace

int main(int argc, char** argv) {
  apps::Args args(argc, argv,
                  {"url", "scene", "script", "record-script", "name", "participants", "frames", "duration-s", "speed", "collision", "step-ms",
                   "frame-ms", "join-timeout-ms", "ack-timeout-ms", "message-timeout-ms", "stop-after-task"},
                  {"wall-clock", "pipeline"});
  sim::ServerOptions o;
  o.scene_file = args.str("scene");
  if (o.scene_file.empty()) apps::Args::die("--scene FILE is required (e.g. deploy/scenes/demo.scene.json)");
  o.script_file = args.str("script");
  o.record_script = args.str("record-script");
  o.name = args.str("name", "sim");
  o.participants = args.list("participants");
  o.wall_clock = args.flag("wall-clock");
  o.pipeline = args.flag("pipeline");
  o.speed = args.real("speed", 1.0);
  o.collision_detector = args.str("collision");
  o.step_ms = args.real("step-ms", 0);
  o.frame_ms = args.real("frame-ms", 0);
  o.frames = args.num("frames", -1);
  o.duration_s = args.real("duration-s", 0);
  o.stop_after_task = args.num("stop-after-task", -1);
  o.join_timeout = std::chrono::milliseconds(args.num("join-timeout-ms", 10000));
  o.ack_timeout = std::chrono::milliseconds(args.num("ack-timeout-ms", 5000));
  o.message_timeout = std::chrono::milliseconds(args.num("message-timeout-ms", 2000));

  std::unique_ptr<Bus> bus;
  std::unique_ptr<sim::SimServer> server;
  apps::start_or_exit("sim_server", [&] {
    bus = open_bus(args.str("url"));
    server = std::make_unique<sim::SimServer>(*bus, o);
  });
  apps::stop_on_signals();
  const sim::ServerReport rep = server->run_until([] { return apps::stop_requested() != 0; });
  const auto& r = rep.run;
  // Where each object ended (x y z in the world), for people and for the demo's summary.
  skillbus_msgs::sim_state_t state{};
  server->physics().fill_state(state);
  std::string objects;
  for (const auto& o : state.objects) {
    char buf[256];
    std::snprintf(buf, sizeof buf, "%s\"%s\": [%.4f, %.4f, %.4f]", objects.empty() ? "" : ", ",
                  apps::json_escape(o.name).c_str(), o.pose[0], o.pose[1], o.pose[2]);
    objects += buf;
  }
  // Where a frame's wall time went, in ms per frame: publishing the state, the physics
  // (and commands), the wait for the participants' acks (the slowest of each frame), and
  // each participant's own clock-to-ack time (its work plus the transport both ways).
  std::string breakdown;
  {
    const double f = rep.run.frames > 0 ? static_cast<double>(rep.run.frames) : 1.0;
    char buf[256];
    std::snprintf(buf, sizeof buf, "\"state\": %.3f, \"physics\": %.3f, \"ack_wait\": %.3f, \"total\": %.3f",
                  rep.frame_start_seconds * 1e3 / f, rep.frame_end_seconds * 1e3 / f, rep.ack_wait_seconds * 1e3 / f,
                  rep.run.wall_seconds * 1e3 / f);
    breakdown = buf;
    for (const auto& [name, s] : rep.ack_seconds) {
      std::snprintf(buf, sizeof buf, ", \"ack_%s\": %.3f", apps::json_escape(name).c_str(), s * 1e3 / f);
      breakdown += buf;
    }
  }
  const double rtf = r.wall_seconds > 0 ? r.sim_time_ns * 1e-9 / r.wall_seconds : 0.0;
  std::printf(
      "{\"ok\": %s, \"error\": \"%s\", \"frames\": %lld, \"sim_time_s\": %.3f, \"wall_time_s\": %.3f, "
      "\"real_time_factor\": %.2f, \"steps\": %lld, \"physics_us_per_step\": %.1f, \"collision_detector\": \"%s\", "
      "\"participants\": %zu, \"state_digest\": \"%s\", \"session_digest\": \"%s\", \"commands_accepted\": %ld, "
      "\"commands_rejected\": %ld, \"bad_input\": %ld, \"finger_width\": %.5f, \"finger_force\": %.3f, "
      "\"objects\": {%s}, \"frame_ms\": {%s}}\n",
      r.ok ? "true" : "false", apps::json_escape(r.error).c_str(), static_cast<long long>(r.frames), r.sim_time_ns * 1e-9,
      r.wall_seconds, rtf, static_cast<long long>(rep.steps), rep.steps ? rep.physics_seconds * 1e6 / rep.steps : 0.0,
      server->physics().collision_detector().c_str(), o.participants.size(), to_hex(rep.state_digest).c_str(),
      r.digest_hex().c_str(), rep.accepted, rep.rejected, rep.bad_input, state.finger_width, state.finger_force,
      objects.c_str(), breakdown.c_str());
  std::fflush(stdout);
  return r.ok ? 0 : 1;
}
