#include "skillbus/apps/cli.hpp"

#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <iostream>
#include <sstream>

#include "skillbus/bus.hpp"

namespace skillbus::apps {

namespace {

std::string one_line(std::string s) {
  for (char& c : s)
    if (c == '\n' || c == '\r') c = ' ';
  while (!s.empty() && s.back() == ' ') s.pop_back();
  return s;
}

}  // namespace

void configure(CLI::App& app) {
  app.option_defaults()->always_capture_default();
  app.get_formatter()->column_width(38);
}

void parse_or_exit(CLI::App& app, int argc, char** argv) {
  try {
    app.parse(argc, argv);
  } catch (const CLI::CallForHelp&) {
    std::cout << app.help() << std::flush;
    std::exit(0);
  } catch (const CLI::CallForAllHelp&) {
    std::cout << app.help("", CLI::AppFormatMode::All) << std::flush;
    std::exit(0);
  } catch (const CLI::ParseError& e) {
    usage_error(app, e.what());
  }
}

void usage_error(const CLI::App& app, const std::string& why) {
  std::fprintf(stderr, "%s: error: %s (see --help)\n", app.get_name().c_str(), one_line(why).c_str());
  std::exit(kUsageError);
}

const CLI::Validator& positive() {
  static const CLI::Validator v(
      [](std::string& text) -> std::string {
        double x = 0;
        if (!CLI::detail::lexical_cast(text, x) || !std::isfinite(x) || !(x > 0))
          return "must be a positive number, not '" + text + "'";
        return "";
      },
      "POSITIVE");
  return v;
}

CLI::Option* add_url_option(CLI::App& app, std::string& url) {
  // --network IFACE: the bus may use that network interface (local by default; it sets
  // $SKILLBUS_NETWORK, which open_bus reads).
  app.add_option_function<std::string>(
         "--network", [](const std::string& iface) { ::setenv("SKILLBUS_NETWORK", iface.c_str(), 1); },
         "let the bus join its multicast group on this network interface (default: loopback only; "
         "docs/security.md)")
      ->type_name("IFACE");
  return app.add_option("--url", url,
                        "the bus URL (empty: $SKILLBUS_BUS_URL, else udpm://239.255.76.67:7667?ttl=0)");
}

CLI::Option* add_robot_option(CLI::App& app) {
  // Checked now, so that a wrong $SKILLBUS_ROBOT fails at start like a wrong --robot.
  if (const char* env = std::getenv("SKILLBUS_ROBOT"); env && *env && !valid_robot_name(env)) {
    std::fprintf(stderr, "%s: error: $SKILLBUS_ROBOT '%s': a robot name is a letter, then letters, digits or _\n",
                 app.get_name().c_str(), env);
    std::exit(kUsageError);
  }
  return app
      .add_option_function<std::string>(
          "--robot",
          [&app](const std::string& robot) {
            try {
              set_robot(robot);
            } catch (const std::invalid_argument& e) {
              usage_error(app, std::string("--robot: ") + e.what());
            }
          },
          "the robot whose channels it uses: NAME/SB_ROBOT_..., NAME/SB_SKILL_... (default: $SKILLBUS_ROBOT, "
          "else the one robot, without a name)")
      ->type_name("NAME");
}

CLI::Option* add_list_option(CLI::App& app, const std::string& name, std::vector<std::string>& out,
                             const std::string& description) {
  return app
      .add_option_function<std::string>(
          name,
          [&out](const std::string& text) {
            out.clear();
            std::stringstream ss(text);
            for (std::string item; std::getline(ss, item, ',');)
              if (!item.empty()) out.push_back(item);
          },
          description)
      ->type_name("A,B,...")
      ->multi_option_policy(CLI::MultiOptionPolicy::TakeLast);
}

CLI::Option* add_ack_timeouts_option(CLI::App& app, std::vector<std::string>& items) {
  return app.add_option("--ack-timeout-ms-of", items,
                        "lockstep: NAME=MS, a participant whose frames may take longer than --ack-timeout-ms "
                        "(repeatable; e.g. map=60000)");
}

CLI::Option* add_ack_poll_option(CLI::App& app, int64_t& us) {
  return app
      .add_option("--ack-poll-us", us,
                  "lockstep: once its own work of a frame is done, poll this long for the acks before sleeping "
                  "(0: sleep at once; for a process on a core of its own: docs/lockstep.md)")
      ->check(CLI::Range(int64_t{0}, int64_t{1'000'000}));
}

CLI::Option* add_cpu_latency_option(CLI::App& app, int64_t& us) {
  return app
      .add_option("--cpu-latency-us", us,
                  "while it runs, ask the kernel to keep every core's wake-up latency at most this long (Linux PM "
                  "QoS, /dev/cpu_dma_latency; 0: idle cores poll instead of halting, which makes wake-ups across "
                  "cores cheap and costs power; -1: do not ask; docs/lockstep.md)")
      ->check(CLI::Range(int64_t{-1}, int64_t{1'000'000}));
}

std::map<std::string, std::chrono::milliseconds> parse_ack_timeouts(const CLI::App& app,
                                                                    const std::vector<std::string>& items) {
  std::map<std::string, std::chrono::milliseconds> out;
  for (const auto& item : items) {
    const auto eq = item.find('=');
    int64_t ms = 0;
    try {
      size_t used = 0;
      if (eq == std::string::npos || eq == 0) throw std::invalid_argument("no NAME=");
      ms = std::stoll(item.substr(eq + 1), &used);
      if (used != item.size() - eq - 1 || ms <= 0) throw std::invalid_argument("not a positive number");
    } catch (const std::exception&) {
      usage_error(app, "--ack-timeout-ms-of " + item + ": expected NAME=MS with MS a positive whole number");
    }
    out[item.substr(0, eq)] = std::chrono::milliseconds(ms);
  }
  return out;
}

}  // namespace skillbus::apps
