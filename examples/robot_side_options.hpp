// The protocol v2 options both robot sides declare, the sbRIO emulator and the sbRIO gateway
// (CLI11; header-only: the armhf build compiles the gateway as one translation unit).
#pragma once

#include <CLI/CLI.hpp>
#include <string>
#include <string_view>
#include <vector>

#include "cli_numbers.hpp"

namespace examples {

//! Declares --key, --rig and --max-round-trip on `app`. `prefix` starts each help text (the
//! emulator's "protocol v2: ", as it speaks the 2016 wire too); `zero_round_trip` says what
//! --max-round-trip 0 grants.
inline void add_robot_side_v2_options(CLI::App& app, std::vector<std::string>& key_paths,
                                      std::string& rig_name, double& max_round_trip_ms,
                                      std::string_view prefix, std::string_view zero_round_trip) {
  const std::string p(prefix);
  app.add_option("--key", key_paths,
                 p + "the 32-byte key file (mode 0600) the console holds; give it twice while a "
                     "key is changed over (the key in use and its successor)");
  app.add_option("--rig", rig_name,
                 p + "this robot side's name (1-16 printable characters), bound into every "
                     "session key: a console for another rig is refused")
      ->capture_default_str();
  app.add_option("--max-round-trip", max_round_trip_ms,
                 p +
                     "the longest round trip granted, ms: a setpoint is obeyed only if the state "
                     "it acknowledges answered a setpoint received at most this long ago (0: " +
                     std::string(zero_round_trip) + ")")
      ->check(number_in(0.0, 10000.0))
      ->capture_default_str();
}

}  // namespace examples
