// The bridges' command line: the link and loop settings endohaptics-bridge and
// endohaptics-ros-bridge share (declared in link_options.hpp), and endohaptics-bridge's parse
// (options.cpp; examples/program_options.hpp).
#pragma once

#include <endohaptics/protocol/handshake.hpp>
#include <string>

#include "../program_options.hpp"

namespace bridge {

struct Options {
  std::string sbrio = "169.254.4.42:61556";
  std::string local;  // --local HOST:PORT: where the bridge sends from (empty: any free port)
  std::string rate = "1000";
  double duration = 0.0;
  std::string device = "sim";
  std::string passivity = "off";      // --passivity: off or tdpa (docs/passivity.md)
  double passivity_round_trip = 0.0;  // ms, --passivity-round-trip
  std::string config_path;
  std::string instrument;  // --instrument: whose model set (estimator.model_sets) to run
  std::string log_path;
  bool stats = false;
  int fifo_priority = 0;
  int cpu = -1;
  double busy_wait_us = 0.0;
  std::string protocol = "2";  // "2": v2 (authenticated, docs/protocol.md); "2016": legacy
  std::string key_path;        // v2: the pre-shared key file
  std::string rig =
      std::string(endohaptics::protocol::default_rig_name);  // v2: the robot side's name
  std::string generate_key;                                  // write a new key file and exit
  int max_answer_lag = 0;  // v2: a state may answer a setpoint this many older than the newest
};

//! endohaptics-bridge's command line (the link options and --device) into `opt`.
[[nodiscard]] examples::Parsed parse_options(int argc, const char* const* argv, Options& opt);

}  // namespace bridge
