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

//! The settings both programs' requests take as given (identify's IdentifyRequest, replay's
//! ReplayRequest): the logs and their signals, the causal score's initial state and warm-up, and
//! what to do with non-finite rows. The preprocessing differs between them (identify shows its
//! defaults, replay takes the model file's): each program sets that itself.
template <typename Request>
void copy_shared_settings(const LogWorkflowOptions& o, Request& q) {
  q.logs = o.logs;
  q.format = o.format;
  q.inputs = o.inputs;
  q.outputs = o.outputs;
  q.x0 = o.x0;
  q.warmup = o.warmup;
  q.drop_non_finite = o.drop_non_finite;
}

}  // namespace examples
