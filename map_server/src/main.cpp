// map_server: the occupancy map (OctoMap) of what the depth cameras see, over RPC (area
// MAP). See docs/perception.md, "The occupancy map".
//
// Reads: SB_CAMERA_CLOUD (camera_cloud_t), SB_MAP_REQ. Writes: SB_MAP_REP.
// With --lockstep NAME it is a lockstep participant: clouds are inserted in canonical
// order within frames, and a query asked as of frame n waits until this server has
// finished frame n. After the session it goes on answering (the map as of the last frame)
// until SIGTERM or SIGINT, unless --exit-with-session.
#include "map_service.hpp"
#include "skillbus/apps/cli.hpp"
#include "skillbus/apps/lifecycle.hpp"
#include "skillbus/apps/summary.hpp"
#include "skillbus/auth.hpp"
#include "skillbus/lockstep.hpp"

using namespace skillbus;

int main(int argc, char** argv) {
  CLI::App app{"The occupancy map (OctoMap) of what the depth cameras see, over RPC (area MAP: info, state, box, "
               "free_area, save, load, clear). SIGTERM or SIGINT stop it; it prints a one-line JSON summary.",
               "map_server"};
  apps::configure(app);
  std::string url, lockstep_name, load_name;
  std::vector<std::string> cameras;
  bool exit_with_session = false;
  map::ServiceOptions o;
  apps::add_url_option(app, url);
  app.add_option("--resolution", o.resolution, "m, the edge of a voxel")->check(apps::positive());
  app.add_option("--maps", o.maps_dir, "the folder save and load find maps in, by name (NAME.bt)")->type_name("DIR");
  apps::add_list_option(app, "--cameras", cameras, "insert only these cameras' clouds (default: every camera's)");
  app.add_option("--load", load_name, "start from this map of the maps folder")->type_name("NAME");
  app.add_option("--lockstep", lockstep_name, "be the lockstep participant NAME")->type_name("NAME");
  app.add_flag("--exit-with-session", exit_with_session, "lockstep: exit when the session ends");
  apps::parse_or_exit(app, argc, argv);
  o.cameras.insert(cameras.begin(), cameras.end());
  std::unique_ptr<Bus> bus;
  std::unique_ptr<map::MapService> service;
  apps::start_or_exit("map_server", [&] {
    bus = open_bus(url);
    service = std::make_unique<map::MapService>(*bus, o);
    if (!load_name.empty()) service->load(load_name);
  });
  apps::stop_on_signals();
  const std::string clouds = channel("SB_CAMERA_CLOUD");
  RunResult run;
  bool ran_lockstep = false;
  if (!lockstep_name.empty()) {
    ParticipantConfig pc;
    pc.name = lockstep_name;
    pc.kind = "map";
    LockstepParticipant p(*bus, pc);
    service->set_lockstep(true);
    p.subscribe(clouds, [&](const StampedMessage& m) { service->on_cloud_part(m.data.data(), m.data.size(), m.channel); });
    p.interrupted = [] { return apps::stop_requested() != 0; };  // (also while it waits for a clock)
    p.after_frame = [&](int64_t frame) {
      service->set_completed_frame(frame);
      service->rpc().retry_deferred();
    };
    SB_INFO("map_server", "joining the lockstep as " << lockstep_name << "; serving " << rpc_request_channel("MAP"));
    run = p.run();
    ran_lockstep = true;
    // After the session: the map as of its last frame, for whoever asks (a query for a
    // later frame than the session had is answered with what there is).
    service->set_completed_frame(std::numeric_limits<int64_t>::max() - 1);
    service->rpc().retry_deferred();
    service->set_lockstep(false);
  } else {
    bus->subscribe(clouds, [&](const std::string& ch, const uint8_t* d, size_t n) { service->on_cloud_part(d, n, ch); });
    SB_INFO("map_server", "serving " << rpc_request_channel("MAP") << " (wall clock), resolution " << o.resolution << " m");
  }
  if (!(ran_lockstep && exit_with_session))
    while (!apps::stop_requested()) bus->handle(std::chrono::milliseconds(100));
  apps::Summary out;
  out["ok"] = !ran_lockstep || run.ok;
  if (ran_lockstep) {
    out["error"] = run.error;
    out["frames"] = run.frames;
    out["digest"] = to_hex(run.digest);
  }
  out["clouds"] = service->clouds();
  out["leaves"] = static_cast<int64_t>(service->map().leaves());
  out["map_digest"] = to_hex(service->map().digest());
  out["served"] = service->rpc().served();
  out["bad_input"] = service->bad_input().total() + service->rpc().bad_input().total();
  if (const auto* a = auth::stats_of(*bus)) out["bus_rejected"] = a->rejected;
  apps::print_summary(out);
  return ran_lockstep && !run.ok ? 1 : 0;
}
