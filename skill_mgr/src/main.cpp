// skill_mgr: the skill manager. See skill_mgr/README.md.
#include <cstdio>

#include "../../common/apps/args.hpp"
#include "manager.hpp"

using namespace skillbus;

int main(int argc, char** argv) {
  apps::Args args(argc, argv, {"url", "name", "period-ms", "tick-hz", "tick-timeout-ms", "ontology", "start", "robot", "liveness-ms"}, {"wall-clock"});
  skills::ManagerOptions o;
  o.name = args.str("name", "skill_mgr");
  o.wall_clock = args.flag("wall-clock");
  o.frame_period_ns = static_cast<int64_t>(args.real("period-ms", 10.0) * 1e6);
  const double hz = args.real("tick-hz", 25.0);
  if (hz <= 0) apps::Args::die("--tick-hz must be positive");
  o.tick_period_ns = static_cast<int64_t>(1e9 / hz);
  if (o.tick_period_ns % o.frame_period_ns != 0)
    apps::Args::die("the tick period (1/--tick-hz) must be a whole number of frames (--period-ms)");
  o.tick_timeout = std::chrono::milliseconds(args.num("tick-timeout-ms", 1000));
  o.ontology_files = args.list("ontology");
  o.start_at_first_tick = args.str("start");
  o.robot = args.str("robot");
  o.liveness_timeout = std::chrono::milliseconds(args.num("liveness-ms", 3000));
  if (o.liveness_timeout.count() <= 0) apps::Args::die("--liveness-ms must be positive");
  if (o.ontology_files.empty()) o.ontology_files.push_back(SKILLBUS_DEFAULT_ONTOLOGY);
  std::unique_ptr<Bus> bus;
  std::unique_ptr<skills::Manager> mgr;
  apps::start_or_exit("skill_mgr", [&] {
    bus = open_bus(args.str("url"));
    mgr = std::make_unique<skills::Manager>(*bus, o);
  });
  apps::stop_on_signals();
  const RunResult r = mgr->run_until([] { return apps::stop_requested() != 0; });
  std::string tasks;
  for (const auto& [id, result] : mgr->results())
    tasks += (tasks.empty() ? "" : ", ") + std::string("\"") + std::to_string(id) + "\": \"" + apps::json_escape(result) + "\"";
  std::printf("{\"ok\": %s, \"error\": \"%s\", \"frames\": %lld, \"digest\": \"%s\", \"tasks\": {%s}}\n",
              r.ok ? "true" : "false", apps::json_escape(r.error).c_str(), static_cast<long long>(r.frames), r.digest_hex().c_str(),
              tasks.c_str());
  return r.ok ? 0 : 1;
}
