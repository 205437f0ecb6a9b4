// endohaptics-identify: identifies a force model from logs (worksheet 4.2): reads each log and
// prints what the reader dropped, resamples to --ts, low-pass/offset as 4.2.1, identifies with
// N4SID/MOESP/CVA (or all three, keeping the best mean fit), optionally with input dead zones,
// prints the Hankel singular values, the order and the fit per file, and writes a JSON model.
// Workflow: endohaptics/workflow/workflow.hpp; results: docs/identification_results.md.
#include <fmt/format.h>

#include <CLI/CLI.hpp>
#include <cstdio>
#include <endohaptics/workflow/command_line.hpp>
#include <endohaptics/workflow/workflow.hpp>
#include <exception>
#include <string>
#include <vector>

#include "../cli_numbers.hpp"

namespace id = endohaptics::identification;
namespace wf = endohaptics::workflow;
namespace files = endohaptics::files;
namespace limits = endohaptics::workflow::limits;
using examples::number_in;

int main(int argc, char** argv) {
  CLI::App app{"endohaptics identify: subspace (+ dead zone) model from logs"};
  std::vector<std::string> logs, inputs, outputs;
  std::string format = "endowrist-2016", order = "auto", method = "moesp", deadzone = "none";
  std::string offset = "none", input_offset = "none", x0 = "estimate", out_path;
  double ts = 0.0;
  int max_order = 10;
  wf::Preprocessing pre;
  bool drop_non_finite = false;
  app.add_option("--log", logs, "log file (repeat for several experiments)")->required();
  app.add_option("--format", format, "endowrist-2016 or csv (header line names the columns)")
      ->capture_default_str();
  app.add_option("--input", inputs, "input signal (repeat; default for endowrist-2016: current)");
  app.add_option("--output", outputs, "output signal (repeat; default for endowrist-2016: force)");
  app.add_option("--order", order,
                 "model order N, or auto (largest log gap of the singular values)")
      ->check(number_in(1, limits::max_order, {"auto"}))
      ->capture_default_str();
  app.add_option("--max-order", max_order, "largest order --order auto considers")
      ->check(number_in(1, limits::max_order))
      ->capture_default_str();
  app.add_option("--method", method, "n4sid, moesp, cva, best (highest mean fit) or static")
      ->capture_default_str();
  app.add_option("--deadzone", deadzone,
                 "input dead zone: auto, none or half width (or one per input, comma-separated)")
      ->capture_default_str();
  auto* ts_opt = app.add_option("--ts", ts,
                                "resampling period, s (csv without time column: the row time, "
                                "default 1; else default: median step of the first log)")
                     ->check(number_in(limits::min_sample_time, limits::max_sample_time));
  app.add_option("--lowpass", pre.cutoff,
                 "zero-phase Butterworth low-pass cutoff, Hz (0: none; worksheet 4.2.1 used 20)")
      ->check(number_in(0.0, limits::max_cutoff))
      ->capture_default_str();
  app.add_option("--filter-order", pre.filter_order, "Butterworth order")
      ->check(number_in(limits::min_filter_order, limits::max_filter_order))
      ->capture_default_str();
  app.add_option("--offset", offset,
                 "output offset removal: none, start, median or mean (per file)")
      ->capture_default_str();
  app.add_option("--input-offset", input_offset,
                 "input offset removal: none, start, median or mean")
      ->capture_default_str();
  app.add_option("--offset-window", pre.offset_duration, "s at the start used by --offset start")
      ->check(number_in(limits::min_offset_duration, limits::max_duration))
      ->capture_default_str();
  app.add_flag("--detrend", pre.detrend,
               "remove a least-squares line from the outputs of each segment");
  app.add_option("--max-gap", pre.max_gap,
                 "s; longer time steps split a log (0: 5 x max(ts, median step))")
      ->check(number_in(0.0, limits::max_duration))
      ->capture_default_str();
  app.add_option("--min-segment", pre.min_segment,
                 "samples; shorter gap-free stretches are dropped")
      ->check(number_in<Eigen::Index>(limits::min_segment, limits::max_grid_samples))
      ->capture_default_str();
  app.add_flag("--drop-non-finite", drop_non_finite,
               "drop rows holding NaN/Inf instead of failing");
  app.add_option("--x0", x0, "initial state of the per-file fits: estimate or zero")
      ->capture_default_str();
  app.add_option("--out", out_path, "write the model here (JSON)");
  CLI11_PARSE(app, argc, argv);

  try {
    wf::LogSelection sel;
    sel.format = files::parse_log_format(format);
    sel.drop_non_finite = drop_non_finite;
    const bool endowrist = sel.format == files::LogFormat::endowrist_2016;
    sel.inputs = !inputs.empty() ? inputs
                 : endowrist     ? std::vector<std::string>{"current"}
                                 : inputs;
    sel.outputs = !outputs.empty() ? outputs
                  : endowrist      ? std::vector<std::string>{"force"}
                                   : outputs;
    if (sel.inputs.empty() || sel.outputs.empty()) {
      throw endohaptics::Error("--format csv needs --input and --output column names");
    }
    pre.output_offset = wf::offset_mode_from_string(offset);
    pre.input_offset = wf::offset_mode_from_string(input_offset);
    wf::WorkflowOptions options;
    options.max_order = max_order;
    if (order != "auto") options.order = wf::parse_number(order, "--order", 1, limits::max_order);
    if (method == "best") {
      options.candidates = {id::Weighting::n4sid, id::Weighting::moesp, id::Weighting::cva};
    } else if (method == "static") {
      options.static_gain = true;
    } else {
      options.candidates = {id::weighting_from_string(method)};
    }
    options.deadzone = wf::parse_deadzone(deadzone, sel.inputs.size());
    options.initial_state = wf::initial_state_from_string(x0);
    if (options.initial_state == wf::InitialStateMode::stored) {
      throw endohaptics::Error("--x0 must be estimate or zero here");
    }

    // Sample time: given, else the median step of the first log (a CSV without time column:
    // its row time, 1 s unless --ts says otherwise).
    const bool ts_given = ts_opt->count() > 0;
    sel.csv_row_time = ts_given ? ts : 1.0;
    if (!ts_given) ts = wf::default_sample_time(logs.front(), sel);
    std::vector<wf::PreparedLog> prepared;
    for (const auto& path : logs) {
      prepared.push_back(wf::prepare_log(path, sel, ts, pre));
      fmt::print("{}", wf::summary(prepared.back()));
    }
    fmt::print("preprocessing: {}\n", wf::describe(pre));

    auto units = [&](const std::vector<std::string>& names) {
      std::vector<files::SignalInfo> info;
      const files::Log first = endowrist ? files::read_endowrist_2016(logs.front()) : files::Log{};
      for (const auto& n : names) {
        std::string unit;
        for (std::size_t i = 0; i < first.names.size(); ++i) {
          if (first.names[i] == n) unit = first.units[i];
        }
        info.push_back({n, unit});
      }
      return info;
    };
    const auto in_info = units(sel.inputs);
    const auto out_info = units(sel.outputs);
    const wf::WorkflowResult result = wf::identify_logs(prepared, in_info, out_info, options);

    for (const wf::CandidateModel& c : result.candidates) {
      if (!options.static_gain) {
        const auto& sv = c.linear.order_singular_values;
        std::string line;
        for (Eigen::Index i = 0; i < std::min<Eigen::Index>(sv.size(), max_order + 5); ++i) {
          line += fmt::format(" {:.4g}", sv[i]);
        }
        fmt::print("{}: Hankel singular values (MOESP, {} block rows):{}\n", c.method,
                   c.linear.block_rows, line);
        fmt::print("{}: order {} ({}), spectral radius {:.5f}{}\n", c.method, c.linear.order,
                   options.order == 0 ? "automatic" : "given", c.spectral_radius,
                   c.spectral_radius >= 1.0 ? " (NOT STABLE)" : "");
      }
      for (std::size_t j = 0; j < c.model.input_nonlinearity.size(); ++j) {
        const auto& m = c.model.input_nonlinearity[j];
        fmt::print("{}: input {} dead zone [{:.4g}, {:.4g}]\n", c.method, sel.inputs[j], m.lower,
                   m.upper);
      }
      fmt::print("{}: mean fit {:.2f} %\n", c.method, c.mean_fit);
    }
    for (const std::string& f : result.failures) fmt::print("failed: {}\n", f);
    const wf::CandidateModel& best = result.chosen();
    if (!options.static_gain && (best.linear.input_scale.array() != 1.0).any()) {
      fmt::print(
          "scaling: each column divided by its RMS for the fit (inputs {:.4g}, outputs "
          "{:.4g}); the model is in the logs' units\n",
          fmt::join(best.linear.input_scale.begin(), best.linear.input_scale.end(), " "),
          fmt::join(best.linear.output_scale.begin(), best.linear.output_scale.end(), " "));
    }
    fmt::print("chosen: {} (order {}){}\n", best.method, best.model.state_space.state_size(),
               best.spectral_radius >= 1.0 ? ", NOT STABLE: no stable candidate" : "");
    for (const wf::FileComparison& f : best.files) {
      std::string fits;
      for (Eigen::Index i = 0; i < f.fit.size(); ++i) {
        fits += fmt::format(" {} {:.2f} %", sel.outputs[static_cast<std::size_t>(i)], f.fit[i]);
      }
      fmt::print("fit {}:{}\n", f.source, fits);
    }
    // No false success: a fit that is not finite (a diverging model, a constant output) fails.
    for (const wf::FileComparison& f : best.files) wf::require_finite_scores(f, sel.outputs);
    fmt::print("mean fit: {:.2f}%\n", best.mean_fit);
    if (!out_path.empty()) {
      files::ModelFile model = best.model;
      model.provenance.notes = "preprocessing: " + wf::describe(pre) +
                               "\nfit_percent: mean over the identification logs, x0 " + x0 +
                               "\ntool: endohaptics-identify";
      files::save_model(out_path, model);
      fmt::print("model written to {}\n", out_path);
    }
    wf::require_written(stdout, "standard output");
  } catch (const std::exception& e) {
    fmt::print(stderr, "endohaptics-identify: error: {}\n", e.what());
    return 1;
  }
  return 0;
}
