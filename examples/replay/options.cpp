// endohaptics-replay's options (examples/program_options.hpp).
#include "options.hpp"

#include "../parse_command_line.hpp"
#include "../workflow_cli.hpp"

namespace replay {

namespace wf = endohaptics::workflow;

examples::Parsed parse_options(int argc, const char* const* argv, Options& opt) {
  CLI::App app{"endohaptics replay: a model on logs, fit as MATLAB compare"};
  examples::LogWorkflowOptions o;
  wf::ReplayRequest& q = opt.request;
  app.add_option("--model", q.model,
                 "model file (JSON), preset:yaw2016, preset:pitch2016 or preset:clamp2016-as-run")
      ->required();
  examples::add_signal_options(app, examples::Tool::replay, o);
  examples::add_scoring_options(app, examples::Tool::replay, o);
  // Preprocessing: default what the model file records (identify writes it), else none.
  examples::add_preprocessing_options(app, examples::Tool::replay, o);
  app.add_option("--plot", opt.plot_path, "measured vs simulated as PNG (gnuplot pngcairo)");
  examples::Parsed parsed = examples::parse_command_line(app, argc, argv);
  // The request: preprocessing the model file records unless an option says otherwise.
  examples::copy_shared_settings(o, q);
  if (o.ts > 0.0) q.csv_row_time = o.ts;  // > 0 when given
  if (parsed.was_given("--lowpass")) q.lowpass = o.pre.cutoff;
  if (parsed.was_given("--filter-order")) q.filter_order = o.pre.filter_order;
  if (parsed.was_given("--offset-window")) q.offset_window = o.pre.offset_duration;
  if (parsed.was_given("--detrend")) q.detrend = o.pre.detrend;
  if (parsed.was_given("--max-gap")) q.max_gap = o.pre.max_gap;
  if (parsed.was_given("--min-segment")) q.min_segment = o.pre.min_segment;
  if (parsed.was_given("--offset")) q.offset = o.offset;
  if (parsed.was_given("--input-offset")) q.input_offset = o.input_offset;
  return parsed;
}

}  // namespace replay
