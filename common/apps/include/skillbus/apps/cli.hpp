// The command line of skillbus's C++ programs, on CLI11: every program answers --help
// with its options, their descriptions and defaults (and exits 0 without opening the
// bus); a wrong option or value ends it with one line on stderr that names it, and exit
// code 2 (kUsageError).
//
//   CLI::App app{"what the program does", "sb_clock"};
//   apps::configure(app);
//   int64_t frames = 1000;
//   app.add_option("--frames", frames, "frames to run");
//   apps::parse_or_exit(app, argc, argv);
#pragma once

#include <CLI/CLI.hpp>
#include <chrono>
#include <map>
#include <string>
#include <vector>

namespace skillbus::apps {

constexpr int kUsageError = 2;  // the exit code of a wrong command line

// The programs' conventions: defaults shown in --help for every option added after this
// (so call it first), option names in a wide column.
void configure(CLI::App& app);

// Parses; --help prints the help on stdout and exits 0, an error prints
// "<program>: error: <what> (see --help)" on stderr and exits kUsageError.
void parse_or_exit(CLI::App& app, int argc, char** argv);

// A value that parsed but does not fit, found after parsing: the same one line and exit code.
[[noreturn]] void usage_error(const CLI::App& app, const std::string& why);

// --url, the bus every program opens ("" = $SKILLBUS_BUS_URL, else the default URL).
CLI::Option* add_url_option(CLI::App& app, std::string& url);

// --robot NAME: the robot whose channels this program uses (skillbus/bus.hpp, channel();
// default $SKILLBUS_ROBOT, else none). A name that cannot be part of a channel name is a
// usage error, from the option or from the environment.
CLI::Option* add_robot_option(CLI::App& app);

// Checks a number option: finite and > 0 ("--period-ms: must be a positive number, not 0").
// Programs check required options after parsing (with usage_error), so that a wrong
// option is named before a missing one.
const CLI::Validator& positive();

// A comma-separated list ("a,b,c"; empty items are dropped), as the programs take
// their participants and ontology files; the last occurrence counts.
CLI::Option* add_list_option(CLI::App& app, const std::string& name, std::vector<std::string>& out,
                             const std::string& description);

// --ack-timeout-ms-of NAME=MS (repeatable) of a lockstep master: each participant's own
// ack timeout; a malformed item is a usage error naming it.
CLI::Option* add_ack_timeouts_option(CLI::App& app, std::vector<std::string>& items);
std::map<std::string, std::chrono::milliseconds> parse_ack_timeouts(const CLI::App& app,
                                                                    const std::vector<std::string>& items);

// --ack-poll-us US of a lockstep master (MasterConfig::ack_poll): 0 to 1 s, default 0.
CLI::Option* add_ack_poll_option(CLI::App& app, int64_t& us);

// --cpu-latency-us US: the CPU latency to ask the kernel for while the program runs
// (skillbus/apps/cpu_latency.hpp): 0 to 1 s, default -1 (not asked).
CLI::Option* add_cpu_latency_option(CLI::App& app, int64_t& us);

}  // namespace skillbus::apps
