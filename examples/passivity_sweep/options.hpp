// endohaptics-passivity-sweep's command line (options.cpp; examples/program_options.hpp).
#pragma once

#include <string>

#include "../program_options.hpp"

namespace sweep_options {

//! What the command line asks for.
struct Options {
  bool do_table = false, do_transparency = false;
  std::string trace_path, contact_name = "stiff", mode_name = "tdpa", source_name = "sensor";
  std::string model_path, training_dir;
  int round_trip_ms = 100;
  double loss = 0.0, seconds = 11.5;
  std::string observer_name;
  double tolerance = -1.0;
  double robot_tolerance = -1.0;
  std::string robot_return;
  double reserve = 0.0;
  double recovery = 0.0;
  std::string recover;
  std::string fit_name = "play";
  double contact_level = -1.0;
  std::string stiction;
};

//! Reads the command line into `o`.
[[nodiscard]] examples::Parsed parse_options(int argc, const char* const* argv, Options& o);

}  // namespace sweep_options
