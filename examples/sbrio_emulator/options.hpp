// endohaptics-sbrio-emulator's command line: the settings (Options) and their parse, declared in
// options.cpp (compiled with every program's options in one translation unit:
// examples/program_options.hpp).
#pragma once

#include <cstdint>
#include <endohaptics/protocol/handshake.hpp>
#include <string>
#include <vector>

#include "../program_options.hpp"

namespace emulator {

//! The command line's settings (in the order run() unpacks them).
struct Options {
  std::string bind = "0.0.0.0";
  std::uint16_t port = 61556;
  int motors = 4;
  std::string environment = "tissue";
  std::string truth_path;
  double truth_period_ms = 1.0;
  double duration = 0.0;
  double watchdog_ms = 100.0;
  bool quiet = false;
  double delay_ms = 0.0;
  double jitter_ms = 0.0;
  double loss = 0.0;
  std::string wire = "2";              // --protocol: "2" (v2, authenticated) or "2016" (legacy)
  std::vector<std::string> key_paths;  // v2: the key in use, and its successor during a change
  std::string rig_name = std::string(endohaptics::protocol::default_rig_name);
  std::string generate_key;
  std::string peer;              // --peer: 2016 mode, the only console obeyed
  double max_round_trip_ms = 0;  // --max-round-trip: v2 binding (0: derived)
};

//! Reads the command line into `o`.
[[nodiscard]] examples::Parsed parse_options(int argc, const char* const* argv, Options& o);

}  // namespace emulator
