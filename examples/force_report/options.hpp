// endohaptics-force-report's command line (options.cpp; examples/program_options.hpp).
#pragma once

#include <string>
#include <vector>

#include "../program_options.hpp"

namespace force_report {

//! The command line's settings (in the order main() unpacks them).
struct Options {
  std::vector<std::string> truth_paths, log_paths, labels, config_paths, free_paths;
  std::string plot_dir;
  int joint = 2;
  double skip = 0.5;
  bool all_joints = false;
};

//! Reads the command line into `o`.
[[nodiscard]] examples::Parsed parse_options(int argc, const char* const* argv, Options& o);

}  // namespace force_report
