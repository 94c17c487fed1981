// wm_server: the world model server. See wm_server/README.md.
#include <cstdio>

#include "skillbus/apps/cli.hpp"
#include "skillbus/apps/lifecycle.hpp"
#include "skillbus/apps/summary.hpp"
#include "skillbus/auth.hpp"
#include "skillbus/wm/journal.hpp"
#include "skillbus/wm/server.hpp"

using namespace skillbus;

int main(int argc, char** argv) {
  CLI::App app{"The world model server: elements, relations, the ontology and poses, with a durable journal; "
               "a lockstep participant unless --wall-clock. Prints a one-line JSON summary when it ends.",
               "wm_server"};
  apps::configure(app);
  std::string url;
  wm::ServerOptions o;
  double period_ms = 10.0;
  apps::add_url_option(app, url);
  app.add_option("--data", o.data_dir,
                 "the journal and snapshot directory (empty: start from --scene; else recover it)")
      ->type_name("DIR");
  apps::add_list_option(app, "--ontology", o.ontology_files,
                        "ontology files or folders (OWL in RDF/XML or Turtle; a folder: every .owl, .ttl, .rdf in "
                        "it and below), loaded in order (default: " SKILLBUS_DEFAULT_ONTOLOGY ")");
  apps::add_list_option(app, "--ontology-library", o.ontology_library,
                        "ontology files or folders not loaded at start: one is loaded when a loaded ontology or a "
                        "scene imports (owl:imports) the ontology IRI it declares");
  app.add_option("--scene", o.scene_file, "a Turtle scene loaded when the data directory is empty")->type_name("FILE");
  app.add_option("--name", o.name, "its lockstep participant name");
  CLI::Option* wall_clock = app.add_flag("--wall-clock", o.wall_clock, "run on the wall clock instead of in lockstep");
  app.add_option("--period-ms", period_ms, "wall clock: the frame period, ms")->check(apps::positive());
  app.add_option("--snapshot-every", o.snapshot_every, "commits between snapshots");
  app.add_option("--sparql-max-examined", o.sparql_max_examined,
                 "a SPARQL query that looks at more candidate triples than this is stopped and refused, naming why")
      ->check(CLI::PositiveNumber)
      ->capture_default_str();
  app.add_option("--crash-after-commits", o.crash_after_commits,
                 "tests: die after this many durable commits, before replying (-1: never)");
  double hold_changes_ms = 0;
  app.add_option("--hold-changes-ms", hold_changes_ms,
                 "tests, with --wall-clock: publish each change this long after its commit (a slow change stream)")
      ->check(CLI::NonNegativeNumber)
      ->needs(wall_clock);  // (under lockstep changes go out in frames, for everyone alike)
  bool repair = false;
  app.add_flag("--repair", repair,
               "check the --data directory and exit; a damaged journal is replaced by its intact records before "
               "the damage (the original kept as journal.bin.corrupt); see docs/world_model.md, Durability");
  apps::parse_or_exit(app, argc, argv);
  if (!o.wall_clock && app.count("--period-ms") > 0)  // (ignored without a word under lockstep)
    apps::usage_error(app, "--period-ms is for the wall clock: it needs --wall-clock");
  o.hold_changes_ns = static_cast<int64_t>(hold_changes_ms * 1e6);
  if (repair) {  // no bus, no server: the files only
    const wm::RepairResult r = wm::repair_data_dir(o.data_dir);
    std::fprintf(r.exit_code == 0 ? stdout : stderr, "wm_server: %s\n", r.message.c_str());
    return r.exit_code;
  }
  if (o.ontology_files.empty()) o.ontology_files.push_back(SKILLBUS_DEFAULT_ONTOLOGY);
  o.frame_period_ns = static_cast<int64_t>(period_ms * 1e6);
  if (o.frame_period_ns <= 0) apps::usage_error(app, "--period-ms must be positive");

  std::unique_ptr<Bus> bus;
  std::unique_ptr<wm::WorldModelServer> server;
  apps::start_or_exit("wm_server", [&] {
    bus = open_bus(url);
    server = std::make_unique<wm::WorldModelServer>(*bus, o);
  });
  apps::stop_on_signals();
  const RunResult r = server->run_until([] { return apps::stop_requested() != 0; });
  apps::Summary out;
  out["ok"] = r.ok;
  out["error"] = r.error;
  out["frames"] = r.frames;
  out["version"] = server->store().version();
  out["elements"] = server->store().elements().size();
  out["digest"] = r.digest_hex();
  out["rejected"] = server->rejected();
  // Messages the bus refused (no key, a wrong key, replayed, stale, not this sender's channel).
  if (const auto* a = auth::stats_of(*bus)) out["bus_rejected"] = a->rejected;
  apps::print_summary(out);
  return r.ok ? 0 : 1;
}
