// endohaptics-replay: runs a model (JSON file or preset) on logs as a force estimator would and
// scores it causally: each log on the model's sample time, inputs held and low-passed forward
// only as the model file records, x0 the steady state of the first input sample, a warm-up left
// out, the output compared as logged. Prints fit %, correlation, RMSE and delay per file; the
// last two lines are `mean RMSE: X UNIT` and `mean fit: X%`. --x0 oracle gives the old,
// output-fitted MATLAB compare score instead (labelled). --plot draws measured vs estimate.
// The run is workflow::run_replay (workflow/replay_request.hpp); this program parses, calls and
// prints (replay_print.hpp).
#include <fmt/format.h>

#include <CLI/CLI.hpp>
#include <cstdio>
#include <endohaptics/workflow/command_line.hpp>
#include <endohaptics/workflow/replay_request.hpp>
#include <exception>
#include <string>

#include "../workflow_cli.hpp"
#include "replay_print.hpp"

namespace wf = endohaptics::workflow;

int main(int argc, char** argv) {
  CLI::App app{"endohaptics replay: a model on logs, fit as MATLAB compare"};
  examples::LogWorkflowOptions o;
  wf::ReplayRequest q;
  std::string plot_path;
  app.add_option("--model", q.model,
                 "model file (JSON), preset:yaw2016, preset:pitch2016 or preset:clamp2016-as-run")
      ->required();
  examples::add_signal_options(app, examples::Tool::replay, o);
  examples::add_scoring_options(app, examples::Tool::replay, o);
  // Preprocessing: default what the model file records (identify writes it), else none.
  examples::add_preprocessing_options(app, examples::Tool::replay, o);
  app.add_option("--plot", plot_path, "measured vs simulated as PNG (gnuplot pngcairo)");
  CLI11_PARSE(app, argc, argv);

  try {
    using examples::given;
    q.logs = o.logs;
    q.format = o.format;
    q.inputs = o.inputs;
    q.outputs = o.outputs;
    q.x0 = o.x0;
    q.warmup = o.warmup;
    if (o.ts > 0.0) q.csv_row_time = o.ts;  // > 0 when given
    if (given(app, "--lowpass")) q.lowpass = o.pre.cutoff;
    if (given(app, "--filter-order")) q.filter_order = o.pre.filter_order;
    if (given(app, "--offset-window")) q.offset_window = o.pre.offset_duration;
    if (given(app, "--detrend")) q.detrend = o.pre.detrend;
    if (given(app, "--max-gap")) q.max_gap = o.pre.max_gap;
    if (given(app, "--min-segment")) q.min_segment = o.pre.min_segment;
    if (given(app, "--offset")) q.offset = o.offset;
    if (given(app, "--input-offset")) q.input_offset = o.input_offset;
    q.drop_non_finite = o.drop_non_finite;

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
