// The command-line option groups endohaptics-identify and endohaptics-replay share (CLI11; included
// by their options.cpp only, examples/program_options.hpp): the
// logs and their signals, the grid and preprocessing, the causal score's settings. One
// declaration of each option (name, variable, check, range); where the option means something
// else in the two programs (replay takes the preprocessing the model file records unless told
// otherwise), the help text says so.
#pragma once

#include <CLI/CLI.hpp>
#include <endohaptics/workflow/command_line.hpp>
#include <string>
#include <vector>

#include "cli_numbers.hpp"
#include "log_workflow_options.hpp"

namespace examples {

//! --log, --format, --input, --output.
inline void add_signal_options(CLI::App& app, Tool tool, LogWorkflowOptions& o) {
  const bool id = tool == Tool::identify;
  app.add_option("--log", o.logs,
                 id ? "log file (repeat for several experiments)" : "log file (repeatable)")
      ->required();
  app.add_option("--format", o.format,
                 id ? "endowrist-2016, umn-mis-2018 or csv (header line names the columns); sets "
                      "the recommended defaults of the options marked [format]"
                    : "endowrist-2016, umn-mis-2018 or csv")
      ->capture_default_str();
  app.add_option("--input", o.inputs,
                 id ? "input signal (repeat) [format]"
                    : "input signal per model input (default: the model's names)");
  app.add_option("--output", o.outputs,
                 id ? "output signal (repeat) [format]"
                    : "output signal per model output (default: the model's)");
}

//! --x0, --warmup.
inline void add_scoring_options(CLI::App& app, Tool tool, LogWorkflowOptions& o) {
  const bool id = tool == Tool::identify;
  app.add_option("--x0", o.x0,
                 id ? "initial state for the causal score: steady (first input sample) or zero"
                    : "initial state: steady (first input sample), zero, stored, or oracle (least "
                      "squares on the measured output and the fit preprocessing: NOT causal)")
      ->capture_default_str();
  app.add_option("--warmup", o.warmup,
                 id ? "s at the start of each segment left out of the score (inputs only set the "
                      "state)"
                    : "s per segment left out of the score (not oracle)")
      ->check(number_in(0.0, endohaptics::workflow::max_warmup))
      ->capture_default_str();
}

//! --ts, --lowpass, --filter-order, --offset, --input-offset, --offset-window, --detrend,
//! --max-gap, --min-segment, --drop-non-finite. Identify shows the defaults; replay's come from
//! the model file.
inline void add_preprocessing_options(CLI::App& app, Tool tool, LogWorkflowOptions& o) {
  namespace limits = endohaptics::workflow::limits;
  const bool id = tool == Tool::identify;
  const auto shown = [id](CLI::Option* option) {
    return id ? option->capture_default_str() : option;
  };
  app.add_option("--ts", o.ts,
                 id ? "resampling period, s (csv without time column: the row time, default 1; "
                      "else [format] or the median step of the first log)"
                    : "csv without time column: s per row (default: the model's Ts)")
      ->check(number_in(limits::min_sample_time, limits::max_sample_time));
  app.add_option("--lowpass", o.pre.cutoff,
                 id ? "Butterworth low-pass cutoff, Hz (0: none): zero-phase on the fit data, "
                      "forward only on the scoring data and in replay [format]"
                    : "low-pass cutoff, Hz (0: none)")
      ->check(number_in(0.0, limits::max_cutoff));
  shown(app.add_option("--filter-order", o.pre.filter_order, "Butterworth order")
            ->check(number_in(limits::min_filter_order, limits::max_filter_order)));
  shown(app.add_option("--offset", o.offset,
                       id ? "output offset removal: none, start, median or mean (per file)"
                          : "output offset (--x0 oracle only): none, start, median, mean"));
  shown(app.add_option("--input-offset", o.input_offset,
                       id ? "input offset removal: none, start, median or mean"
                          : "input offset (--x0 oracle only): none, start, median, mean"));
  shown(app.add_option("--offset-window", o.pre.offset_duration,
                       id ? "s at the start used by --offset start" : "s for --offset start")
            ->check(number_in(limits::min_offset_duration, limits::max_duration)));
  app.add_flag("--detrend", o.pre.detrend,
               id ? "remove a least-squares line from the outputs of each segment"
                  : "remove a line from each output (--x0 oracle only)");
  shown(app.add_option("--max-gap", o.pre.max_gap,
                       id ? "s; longer time steps split a log (0: 5 x max(ts, median step))"
                          : "s; longer steps split a log")
            ->check(number_in(0.0, limits::max_duration)));
  shown(
      app.add_option("--min-segment", o.pre.min_segment,
                     id ? "samples; shorter gap-free stretches are dropped" : "samples per segment")
          ->check(number_in<Eigen::Index>(limits::min_segment, limits::max_grid_samples)));
  app.add_flag("--drop-non-finite", o.drop_non_finite,
               "drop rows holding NaN/Inf instead of failing");
}

}  // namespace examples
