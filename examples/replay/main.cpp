// endohaptics-replay: runs a model (JSON file or preset) on logs as a force estimator would and
// scores it causally: each log on the model's sample time, inputs held and low-passed forward
// only as the model file records, x0 the steady state of the first input sample, a warm-up left
// out, the output compared as logged. Prints fit %, correlation, RMSE and delay per file; the
// last two lines are `mean RMSE: X UNIT` and `mean fit: X%`. --x0 oracle gives the old,
// output-fitted MATLAB compare score instead (labelled). --plot draws measured vs estimate.
// The run is workflow::run_replay (workflow/replay_request.hpp); this program parses, calls and
// prints (replay_print.hpp).
#include <fmt/format.h>

#include <cstdio>
#include <endohaptics/workflow/command_line.hpp>
#include <endohaptics/workflow/replay_request.hpp>
#include <exception>
#include <string>

#include "options.hpp"
#include "replay_print.hpp"

namespace wf = endohaptics::workflow;

int main(int argc, char** argv) {
  replay::Options opt;
  const examples::Parsed parsed = replay::parse_options(argc, argv, opt);
  if (parsed.exit_code) return *parsed.exit_code;
  const wf::ReplayRequest& q = opt.request;
  const std::string& plot_path = opt.plot_path;

  try {
    const wf::ReplayReport report = wf::run_replay(
        q, {.resolved = replay_print::resolved,
            .prepared = [](const wf::PreparedLog& log) { fmt::print("{}", wf::summary(log)); },
            .scored = replay_print::scored});
    if (!plot_path.empty()) {
      replay_print::plot(plot_path, report.files, report.selection.outputs);
      fmt::print("plot written to {}\n", plot_path);
    }
    const std::string& unit = report.model.outputs.front().unit;
    fmt::print("mean RMSE: {:.4g}{}{}\n", report.mean_rmse, unit.empty() ? "" : " ", unit);
    fmt::print("mean fit: {:.2f}%\n", report.mean_fit);
    wf::require_written(stdout, "standard output");
  } catch (const std::exception& e) {
    fmt::print(stderr, "endohaptics-replay: error: {}\n", e.what());
    return 1;
  }
  return 0;
}
