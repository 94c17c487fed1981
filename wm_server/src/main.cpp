// wm_server: the world model server. See wm_server/README.md.
#include <cstdio>

#include "../../common/apps/args.hpp"
#include "server.hpp"

using namespace skillbus;

int main(int argc, char** argv) {
  apps::Args args(argc, argv,
                  {"url", "data", "ontology", "scene", "name", "period-ms", "snapshot-every", "crash-after-commits"}, {"wall-clock"});
  wm::ServerOptions o;
  o.data_dir = args.str("data", "wm_data");
  o.ontology_files = args.list("ontology");
  if (o.ontology_files.empty()) o.ontology_files.push_back(SKILLBUS_DEFAULT_ONTOLOGY);
  o.scene_file = args.str("scene");
  o.name = args.str("name", "wm");
  o.wall_clock = args.flag("wall-clock");
  o.frame_period_ns = static_cast<int64_t>(args.real("period-ms", 10.0) * 1e6);
  o.snapshot_every = args.num("snapshot-every", 1000);
  o.crash_after_commits = args.num("crash-after-commits", -1);
  std::unique_ptr<Bus> bus;
  std::unique_ptr<wm::WorldModelServer> server;
  apps::start_or_exit("wm_server", [&] {
    bus = open_bus(args.str("url"));
    server = std::make_unique<wm::WorldModelServer>(*bus, o);
  });
  apps::stop_on_signals();
  const RunResult r = server->run_until([] { return apps::stop_requested() != 0; });
  std::printf("{\"ok\": %s, \"error\": \"%s\", \"frames\": %lld, \"version\": %lld, \"elements\": %zu, \"digest\": \"%s\", "
              "\"rejected\": %ld}\n",
              r.ok ? "true" : "false", r.error.c_str(), static_cast<long long>(r.frames),
              static_cast<long long>(server->store().version()), server->store().elements().size(),
              r.digest_hex().c_str(), server->rejected());
  return r.ok ? 0 : 1;
}
