// skill_mgr: the skill manager. See skill_mgr/README.md.
#include <cstdio>

#include "manager.hpp"
#include "skillbus/apps/cli.hpp"
#include "skillbus/apps/lifecycle.hpp"
#include "skillbus/apps/summary.hpp"
#include "skillbus/auth.hpp"
#include "skillbus_msgs/skill_tick_t.hpp"

using namespace skillbus;

int main(int argc, char** argv) {
  CLI::App app{"The skill manager: runs skill tasks (trees of the skills its skill processes offer) against "
               "the world model, a lockstep participant unless --wall-clock. Prints a one-line JSON summary when it ends.",
               "skill_mgr"};
  apps::configure(app);
  std::string url;
  skills::ManagerOptions o;
  double period_ms = 10.0, hz = 25.0;
  int64_t tick_timeout_ms = 1000, liveness_ms = 3000;
  apps::add_url_option(app, url);
  app.add_option("--name", o.name, "its lockstep participant name");
  app.add_flag("--wall-clock", o.wall_clock, "run on the wall clock instead of in lockstep");
  app.add_option("--period-ms", period_ms, "wall clock: the frame period, ms")->check(apps::positive());
  app.add_option("--tick-hz", hz, "skill ticks per second of (sim) time; a whole number of frames")
      ->check(apps::positive());
  app.add_option("--tick-timeout-ms", tick_timeout_ms, "how long a skill process may take to answer a tick");
  int64_t expand_timeout_ms = 30000;
  app.add_option("--expand-timeout-ms", expand_timeout_ms,
                 "how long a skill process may take to expand a compound skill (TaskPlan plans then)")
      ->check(apps::positive());
  apps::add_list_option(app, "--ontology", o.ontology_files,
                        "ontology files or folders (OWL in RDF/XML or Turtle) for its world copy (default: the "
                        "world model server's ontology, read with the world)");
  app.add_option("--start", o.start_at_first_tick, "a task started at the first tick: TYPE or TYPE:LABEL");
  apps::add_robot_option(app);  // its channels (NAME/SB_SKILL_...) and, by label, its agent
  app.add_option("--robot-element", o.robot,
                 "the element id of the agent this manager drives (default: the skiros:Robot labelled --robot NAME)");
  app.add_option("--end-session-after-task", o.end_session_after_frames,
                 "lockstep: when the --start task ends, ask the clock master to end the session this many frames later");
  app.add_option("--liveness-ms", liveness_ms, "wall clock: drop a skill process's skills after this long without a heartbeat")
      ->check(apps::positive());
  apps::parse_or_exit(app, argc, argv);
  if (o.end_session_after_frames >= 0 && (o.start_at_first_tick.empty() || o.wall_clock))
    apps::usage_error(app, "--end-session-after-task needs --start and lockstep (no --wall-clock)");
  for (const char* wall_only : {"--period-ms", "--liveness-ms"})  // (ignored without a word under lockstep)
    if (!o.wall_clock && app.count(wall_only) > 0)
      apps::usage_error(app, std::string(wall_only) + " is for the wall clock: it needs --wall-clock");
  o.robot_label = current_robot();
  o.frame_period_ns = static_cast<int64_t>(period_ms * 1e6);
  if (o.frame_period_ns <= 0) apps::usage_error(app, "--period-ms must be positive");
  o.tick_period_ns = static_cast<int64_t>(1e9 / hz);
  if (o.tick_period_ns % o.frame_period_ns != 0)
    apps::usage_error(app, "the tick period (1/--tick-hz) must be a whole number of frames (--period-ms)");
  o.tick_timeout = std::chrono::milliseconds(tick_timeout_ms);
  o.expand_timeout = std::chrono::milliseconds(expand_timeout_ms);
  o.liveness_timeout = std::chrono::milliseconds(liveness_ms);
  if (o.liveness_timeout.count() <= 0) apps::usage_error(app, "--liveness-ms must be positive");
  std::unique_ptr<Bus> bus;
  std::unique_ptr<skills::Manager> mgr;
  apps::start_or_exit("skill_mgr", [&] {
    bus = open_bus(url);
    mgr = std::make_unique<skills::Manager>(*bus, o);
  });
  apps::stop_on_signals();
  const RunResult r = mgr->run_until([] { return apps::stop_requested() != 0; });
  apps::Summary tasks = apps::Summary::object();
  for (const auto& [id, result] : mgr->results()) tasks[std::to_string(id)] = result;
  apps::Summary out;
  out["ok"] = r.ok;
  out["error"] = r.error;
  out["frames"] = r.frames;
  out["digest"] = r.digest_hex();
  out["tasks"] = tasks;
  out["idle_ticks"] = mgr->idle_ticks();  // execute ticks a primitive's idle_until spared
  // The ticks sent, by action (an END only where no reply said the instance ended).
  const auto& sent = mgr->ticks_sent();
  apps::Summary ticks = apps::Summary::object();
  ticks["start"] = sent[skillbus_msgs::skill_tick_t::START];
  ticks["execute"] = sent[skillbus_msgs::skill_tick_t::EXECUTE];
  ticks["preempt"] = sent[skillbus_msgs::skill_tick_t::PREEMPT];
  ticks["end"] = sent[skillbus_msgs::skill_tick_t::END];
  out["ticks_sent"] = ticks;
  // Messages the bus refused (no key, a wrong key, replayed, stale, not this sender's channel).
  if (const auto* a = auth::stats_of(*bus)) out["bus_rejected"] = a->rejected;
  apps::print_summary(out);
  return r.ok ? 0 : 1;
}
