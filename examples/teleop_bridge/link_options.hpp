// The link and loop options both bridges declare (CLI11; included by their options.cpp only,
// examples/program_options.hpp).
#pragma once

#include <CLI/CLI.hpp>
#include <endohaptics/protocol/secure_session.hpp>
#include <endohaptics/workflow/bridge_assembly.hpp>

#include "../cli_numbers.hpp"
#include "options.hpp"

namespace bridge {

namespace link_options {

// Ranges of the numeric options (stated in --help; examples::number_in refuses the rest).
constexpr double min_rate_hz = endohaptics::workflow::bridge_min_rate_hz;
constexpr double max_rate_hz = endohaptics::workflow::bridge_max_rate_hz;
constexpr double max_duration_s = 1e7;  // ~116 days; 0 runs until SIGINT
// Setpoints a v2 answer may lag: what the session layer can look back over (16 s at 1 kHz).
constexpr int max_answer_lag = static_cast<int>(endohaptics::protocol::packet_history) - 1;

}  // namespace link_options

//! Declares the link and loop options shared by the bridges on `app`, writing into `opt`.
inline void add_link_options(CLI::App& app, Options& opt) {
  app.add_option("--sbrio", opt.sbrio, "sbRIO address HOST:PORT")->capture_default_str();
  app.add_option("--local", opt.local,
                 "send from this HOST:PORT (default: any free port; give it when the robot side "
                 "obeys one console, e.g. the emulator's --peer)");
  app.add_option("--rate", opt.rate, "loop rate in Hz, or 'max' (as fast as the link allows)")
      ->check(examples::number_in(link_options::min_rate_hz, link_options::max_rate_hz, {"max"}))
      ->capture_default_str();
  app.add_option("--duration", opt.duration, "seconds to run (0: until SIGINT)")
      ->check(examples::number_in(0.0, link_options::max_duration_s))
      ->capture_default_str();
  app.add_option("--passivity", opt.passivity, "time-domain passivity: off or tdpa")
      ->check(CLI::IsMember({"off", "tdpa"}))
      ->capture_default_str();
  app.add_option("--passivity-round-trip", opt.passivity_round_trip,
                 "ms, the link's round trip, for --passivity tdpa")
      ->check(examples::number_in(0.0, 1000.0))
      ->capture_default_str();
  app.add_option("--config", opt.config_path, "JSON: mapping, safety, estimator, operator, loop")
      ->check(CLI::ExistingFile);
  app.add_option("--instrument", opt.instrument,
                 "run this instrument's model set (NAME.json or NAME/ in the --config's "
                 "estimator.model_sets)");
  app.add_option("--log", opt.log_path, "per-tick CSV log");
  app.add_flag("--stats", opt.stats, "print table-3.1 figures every second");
  app.add_option("--fifo-priority", opt.fifo_priority, "SCHED_FIFO priority 1..99 (0: off)")
      ->check(examples::number_in(0, 99));
  app.add_option("--cpu", opt.cpu, "pin the loop thread to this CPU (-1: no pinning)")
      ->check(examples::number_in(-1, 1023));
  app.add_option("--busy-wait-us", opt.busy_wait_us,
                 "spin the last microseconds of each period (lower jitter, one busy core)")
      ->check(examples::number_in(0.0, 1000.0));
  app.add_option("--protocol", opt.protocol,
                 "wire protocol: 2 (authenticated, needs --key) or 2016 (unauthenticated)")
      ->check(CLI::IsMember({"2", "2016"}))
      ->capture_default_str();
  app.add_option("--key", opt.key_path, "protocol v2: the 32-byte key file (mode 0600)");
  app.add_option("--rig", opt.rig,
                 "protocol v2: the robot side's name (its --rig), bound into every session key")
      ->capture_default_str();
  app.add_option("--max-answer-lag", opt.max_answer_lag,
                 "protocol v2: accept a state answering a setpoint up to N older than the newest "
                 "(0: only the newest; raise it on a link slower than one period, e.g. the "
                 "emulator's --delay: N >= the round trip in periods)")
      ->check(examples::number_in(0, link_options::max_answer_lag))
      ->capture_default_str();
  app.add_option("--generate-key", opt.generate_key,
                 "write a new random key file (mode 0600; refuses an existing file) and exit");
}

}  // namespace bridge
