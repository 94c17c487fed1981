// sb_scene: scene files (docs/scene.md) from the command line, read and checked by the one
// reader the physics server and the motion server use (skillbus_scene). skillbus.sim.scene
// (and so `skillbus scene check|turtle`) runs it, so there is one validator and one Turtle
// writer.
//
//   sb_scene check FILE [--json]    checks the file; prints one line, or with --json the
//                                   normalized scene (every default filled in, URDF paths
//                                   absolute, unit quaternions) as a scene file
//   sb_scene turtle FILE [-o OUT]   the world model's Turtle scene (standard output without -o)
//   sb_scene ids FILE               the world model's element ids by label, as one JSON object
//                                   ({"table": "skiros:Table-1", ...}): what a task names them by
//
// FILE "-" is standard input (relative URDF paths then start from the current folder).
// Exit codes: 0; 2 a scene file that does not pass ("sb_scene: error: FILE: field ..." on
// stderr, one line) or a wrong command line; 1 an output file that cannot be written.
#include <cstdio>
#include <fstream>
#include <iostream>
#include <iterator>
#include <nlohmann/json.hpp>

#include "skillbus/apps/cli.hpp"
#include "skillbus/scene/scene.hpp"
#include "skillbus/scene/turtle.hpp"

using namespace skillbus;

namespace {

scene::Scene read(const std::string& file) {
  if (file != "-") return scene::load_scene(file);
  const std::string text{std::istreambuf_iterator<char>(std::cin), std::istreambuf_iterator<char>()};
  return scene::parse_scene(text, "");
}

std::string one_line(std::string s) {
  for (char& c : s)
    if (c == '\n' || c == '\r') c = ' ';
  return s;
}

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{"Scene files (docs/scene.md): check one with the physics server's reader, or write the world "
               "model's Turtle scene for it. FILE '-' reads standard input. A scene that does not pass: one line "
               "naming the file and the field, exit 2.",
               "sb_scene"};
  apps::configure(app);
  app.require_subcommand(0, 1);  // one; checked after parsing, so that a wrong option is named first
  std::string file, out;
  bool as_json = false;
  CLI::App* check = app.add_subcommand("check", "check a scene file; --json: print it normalized (defaults filled "
                                                "in, URDF paths absolute, unit quaternions)");
  check->add_option("FILE", file, "the scene file ('-': standard input)")->required();
  check->add_flag("--json", as_json, "print the normalized scene as JSON instead of one line");
  CLI::App* turtle = app.add_subcommand("turtle", "write the world model's Turtle scene for a scene file");
  turtle->add_option("FILE", file, "the scene file ('-': standard input)")->required();
  turtle->add_option("-o,--output", out, "write here instead of standard output")->type_name("OUT");
  CLI::App* ids = app.add_subcommand("ids", "the world model's element ids of a scene file by label, as JSON");
  ids->add_option("FILE", file, "the scene file ('-': standard input)")->required();
  apps::parse_or_exit(app, argc, argv);
  if (!check->parsed() && !turtle->parsed() && !ids->parsed())
    apps::usage_error(app, "a subcommand is required: check, turtle or ids");

  scene::Scene s;
  std::string text;
  try {
    s = read(file);
    if (turtle->parsed()) {
      text = scene::to_turtle(s);
    } else if (ids->parsed()) {
      nlohmann::ordered_json j = nlohmann::ordered_json::object();
      for (const auto& e : scene::world_elements(s)) j[e.label] = "skiros:" + e.id;
      text = j.dump(-1, ' ', false, nlohmann::ordered_json::error_handler_t::replace) + "\n";
    } else if (as_json) {
      text = scene::to_json(s, 1) + "\n";
    } else {
      std::string robots;
      size_t obstacles = 0;
      for (const auto& f : s.fixtures) obstacles += f.obstacle ? 1 : 0;
      for (const auto& r : s.robots) robots += (robots.empty() ? "'" : ", '") + one_line(r.name) + "'";
      text = (file == "-" ? std::string("<stdin>") : file) + ": a valid scene ('" + one_line(s.name) + "': robot" +
             (s.robots.size() > 1 ? "s " : " ") + robots + ", " + std::to_string(s.fixtures.size() - obstacles) +
             " fixture(s), " + (obstacles ? std::to_string(obstacles) + " obstacle(s), " : "") +
             std::to_string(s.objects.size()) + " object(s)" +
             (s.articulated.empty() ? "" : ", " + std::to_string(s.articulated.size()) + " articulated object(s)") + ")\n";
    }
  } catch (const std::exception& e) {
    std::fprintf(stderr, "sb_scene: error: %s\n", one_line(e.what()).c_str());
    return 2;
  }
  if (out.empty()) {
    std::cout << text << std::flush;
    return std::cout ? 0 : 1;
  }
  std::ofstream f(out, std::ios::binary | std::ios::trunc);
  if (!(f << text) || !f.flush()) {
    std::fprintf(stderr, "sb_scene: error: cannot write %s\n", out.c_str());
    return 1;
  }
  return 0;
}
