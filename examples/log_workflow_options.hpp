// The settings of the option groups endohaptics-identify and endohaptics-replay share
// (workflow_cli.hpp declares them on the command line).
#pragma once

#include <endohaptics/workflow/model_comparison.hpp>
#include <endohaptics/workflow/preprocessing.hpp>
#include <string>
#include <vector>

namespace examples {

//! The program the options are added to: their help texts differ where their meaning does.
enum class Tool { identify, replay };

//! The settings the shared option groups fill.
struct LogWorkflowOptions {
  std::vector<std::string> logs, inputs, outputs;
  std::string format = "endowrist-2016";
  double ts = 0.0;  // s; 0: not given
  endohaptics::workflow::Preprocessing pre;
  std::string offset = "none", input_offset = "none";
  bool drop_non_finite = false;
  std::string x0 = "steady";
  double warmup = endohaptics::workflow::ScoringOptions{}.warmup;
};

}  // namespace examples
