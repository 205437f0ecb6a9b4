// endohaptics-replay: runs a model (JSON file or preset) on logs as a force estimator would and
// scores it causally (issue 15): each log on the model's sample time, inputs held and low-passed
// forward only as the model file records, x0 the steady state of the first input sample, a
// warm-up left out, the output compared as logged. Prints fit %, correlation, RMSE and delay per
// file; the last two lines are `mean RMSE: X UNIT` and `mean fit: X%`. --x0 oracle gives the
// old, output-fitted MATLAB compare score instead (labelled). --plot draws measured vs estimate.
#include <fmt/format.h>

#include <CLI/CLI.hpp>
#include <cstdio>
#include <endohaptics/workflow/command_line.hpp>
#include <endohaptics/workflow/gnuplot.hpp>
#include <endohaptics/workflow/workflow.hpp>
#include <exception>
#include <string>
#include <utility>
#include <vector>

#include "../cli_numbers.hpp"

namespace id = endohaptics::identification;
namespace wf = endohaptics::workflow;
namespace files = endohaptics::files;
namespace limits = endohaptics::workflow::limits;
using examples::number_in;

namespace {

// Measured vs simulated, one panel per file; segments break the lines. workflow/gnuplot.hpp
// draws it: file and signal names travel to gnuplot as data, never as code.
void plot(const std::string& png, const std::vector<wf::FileComparison>& files,
          const std::vector<std::string>& outputs) {
  wf::PlotFigure figure;
  for (const auto& f : files) {
    wf::PlotPanel& panel = figure.panels.emplace_back();
    panel.title = fmt::format("{} (fit {:.1f} %)", f.source, f.mean_fit());
    panel.x_label = "time (s)";
    for (std::size_t i = 0; i < outputs.size(); ++i) {
      const auto column = static_cast<Eigen::Index>(i);
      wf::PlotSeries measured, simulated;
      measured.title = outputs[i] + " measured";
      simulated.title = outputs[i] + " simulated";
      measured.line_width = simulated.line_width = 2;
      for (std::size_t s = 0; s < f.y.size(); ++s) {
        measured.gap();
        simulated.gap();
        for (Eigen::Index k = 0; k < f.y[s].rows(); ++k) {
          const double t = f.start_time[s] + static_cast<double>(k) * f.sample_time;
          measured.add(t, f.y[s](k, column));
          simulated.add(t, f.y_hat[s](k, column));
        }
      }
      panel.series.push_back(std::move(measured));
      panel.series.push_back(std::move(simulated));
    }
  }
  wf::write_png(figure, png);
}

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{"endohaptics replay: a model on logs, fit as MATLAB compare"};
  std::vector<std::string> logs, inputs, outputs;
  std::string model_arg, format = "endowrist-2016", x0 = "steady", plot_path;
  std::string offset = "none", input_offset = "none";
  double ts = 0.0;
  wf::Preprocessing pre;
  wf::ScoringOptions scoring;
  bool drop_non_finite = false;
  app.add_option("--model", model_arg, "model file (JSON), preset:yaw2016 or preset:pitch2016")
      ->required();
  app.add_option("--log", logs, "log file (repeatable)")->required();
  app.add_option("--format", format, "endowrist-2016, umn-mis-2018 or csv")->capture_default_str();
  app.add_option("--input", inputs, "input signal per model input (default: the model's names)");
  app.add_option("--output", outputs, "output signal per model output (default: the model's)");
  app.add_option("--x0", x0,
                 "initial state: steady (first input sample), zero, stored, or oracle (least "
                 "squares on the measured output and the fit preprocessing: NOT causal)")
      ->capture_default_str();
  app.add_option("--warmup", scoring.warmup, "s per segment left out of the score (not oracle)")
      ->check(number_in(0.0, wf::max_warmup))
      ->capture_default_str();
  app.add_option("--ts", ts, "csv without time column: s per row (default: the model's Ts)")
      ->check(number_in(limits::min_sample_time, limits::max_sample_time));
  // Preprocessing: default what the model file records (identify writes it), else none.
  auto* lowpass = app.add_option("--lowpass", pre.cutoff, "low-pass cutoff, Hz (0: none)")
                      ->check(number_in(0.0, limits::max_cutoff));
  auto* filter_order = app.add_option("--filter-order", pre.filter_order, "Butterworth order")
                           ->check(number_in(limits::min_filter_order, limits::max_filter_order));
  auto* offset_opt = app.add_option("--offset", offset,
                                    "output offset (--x0 oracle only): none, start, median, mean");
  auto* input_offset_opt = app.add_option(
      "--input-offset", input_offset, "input offset (--x0 oracle only): none, start, median, mean");
  auto* window = app.add_option("--offset-window", pre.offset_duration, "s for --offset start")
                     ->check(number_in(limits::min_offset_duration, limits::max_duration));
  auto* detrend =
      app.add_flag("--detrend", pre.detrend, "remove a line from each output (--x0 oracle only)");
  auto* max_gap = app.add_option("--max-gap", pre.max_gap, "s; longer steps split a log")
                      ->check(number_in(0.0, limits::max_duration));
  auto* min_segment =
      app.add_option("--min-segment", pre.min_segment, "samples per segment")
          ->check(number_in<Eigen::Index>(limits::min_segment, limits::max_grid_samples));
  app.add_flag("--drop-non-finite", drop_non_finite,
               "drop rows holding NaN/Inf instead of failing");
  app.add_option("--plot", plot_path, "measured vs simulated as PNG (gnuplot pngcairo)");
  CLI11_PARSE(app, argc, argv);

  try {
    const files::ModelFile model = model_arg.starts_with("preset:")
                                       ? wf::preset_model(model_arg.substr(7))
                                       : files::load_model(model_arg);
    const std::string name = model_arg.starts_with("preset:") ? model_arg : "model " + model_arg;
    std::vector<std::string> model_in, model_out;
    for (const auto& s : model.inputs) model_in.push_back(s.name);
    for (const auto& s : model.outputs) model_out.push_back(s.name);
    wf::LogSelection sel;
    sel.format = files::parse_log_format(format);
    sel.drop_non_finite = drop_non_finite;
    sel.inputs = inputs.empty() ? model_in : inputs;
    sel.outputs = outputs.empty() ? model_out : outputs;
    if (sel.inputs.size() != model_in.size() || sel.outputs.size() != model_out.size()) {
      throw endohaptics::Error(fmt::format(
          "{} has {} input(s) ({}) and {} output(s) ({}); the command line names {} and {}", name,
          model_in.size(), fmt::join(model_in, ", "), model_out.size(), fmt::join(model_out, ", "),
          sel.inputs.size(), sel.outputs.size()));
    }
    sel.csv_row_time = ts > 0.0 ? ts : model.state_space.sample_time();  // ts > 0 when given

    // Flags given on the command line win over the recorded preprocessing.
    const wf::Preprocessing given = pre;
    const auto recorded = wf::recorded_preprocessing(model);
    if (recorded) pre = *recorded;
    if (lowpass->count() > 0) pre.cutoff = given.cutoff;
    if (filter_order->count() > 0) pre.filter_order = given.filter_order;
    if (window->count() > 0) pre.offset_duration = given.offset_duration;
    if (detrend->count() > 0) pre.detrend = given.detrend;
    if (max_gap->count() > 0) pre.max_gap = given.max_gap;
    if (min_segment->count() > 0) pre.min_segment = given.min_segment;
    if (offset_opt->count() > 0) pre.output_offset = wf::offset_mode_from_string(offset);
    if (input_offset_opt->count() > 0) {
      pre.input_offset = wf::offset_mode_from_string(input_offset);
    }
    scoring.initial_state = wf::initial_state_from_string(x0);
    const bool causal = wf::is_causal(scoring.initial_state);
    if (causal &&
        (offset_opt->count() > 0 || input_offset_opt->count() > 0 || detrend->count() > 0)) {
      throw endohaptics::Error(
          "--offset, --input-offset and --detrend look at the whole file (or the output): they "
          "apply only to the output-fitted --x0 oracle score; the causal score compares the "
          "output as logged");
    }
    if (model.is_joint_model() && !causal) {
      throw endohaptics::Error(
          "--x0 oracle: " + name + " is a " + std::string(files::to_string(model.kind())) +
          " model: it has no linear state to fit to the output (it starts from its reset "
          "state, filters at the first sample); replay scores it causally (leave out --x0)");
    }
    if (!causal) scoring.warmup = 0.0;  // MATLAB compare: every sample
    if (model.is_joint_model()) {
      fmt::print("{}: kind {}, {} -> {}, Ts {} s, {}\n", name, files::to_string(model.kind()),
                 fmt::join(model_in, ", "), fmt::join(model_out, ", "),
                 model.state_space.sample_time(), model.provenance.method);
    } else {
      fmt::print("{}: {} states, {} -> {}, Ts {} s, {}\n", name, model.state_space.state_size(),
                 fmt::join(model_in, ", "), fmt::join(model_out, ", "),
                 model.state_space.sample_time(), model.provenance.method);
    }
    if (causal && model.is_joint_model()) {
      fmt::print(
          "scoring (causal): the model's state from its reset (filters started at the first "
          "sample; --x0 does not apply), warm-up {} s per segment excluded, inputs held "
          "(lowpass_hz={}), output as logged (no offset, filter or detrend)\n",
          scoring.warmup, pre.cutoff);
    } else if (causal) {
      fmt::print(
          "scoring (causal): x0 {}, warm-up {} s per segment excluded, inputs held and low-passed "
          "forward only (lowpass_hz={} filter_order={}, {}), output as logged (no offset, filter "
          "or detrend)\n",
          x0, scoring.warmup, pre.cutoff, pre.filter_order,
          recorded ? "as the model file records" : "flags");
      if (pre.output_offset != wf::OffsetMode::none || pre.input_offset != wf::OffsetMode::none ||
          pre.detrend) {
        fmt::print(
            "note: the model was fitted on data with offsets/detrend removed ({}); they "
            "are not removed when scoring\n",
            wf::describe(pre));
      }
    } else {
      fmt::print(
          "scoring: ORACLE, not a force-estimation result: x0 fitted to the measured output, "
          "data preprocessed as for the fit ({}: {})\n",
          recorded ? "model file, flags override" : "flags", wf::describe(pre));
    }

    std::vector<wf::FileComparison> results;
    double fit_sum = 0.0, rmse_sum = 0.0;
    for (const auto& path : logs) {
      const wf::PreparedLog log =
          wf::prepare_log(path, sel, model.state_space.sample_time(), pre, 20,
                          causal ? wf::Preparation::score : wf::Preparation::fit);
      fmt::print("{}", wf::summary(log));
      results.push_back(wf::compare_log(model, log, scoring));
      const wf::FileComparison& c = results.back();
      // No false success: a diverging model or an undefined score fails the run.
      wf::require_finite_scores(c, sel.outputs);
      for (Eigen::Index i = 0; i < c.fit.size(); ++i) {
        const auto& o = model.outputs[static_cast<std::size_t>(i)];
        fmt::print("{}: {} fit {:.2f} %, correlation {:.4f}, RMSE {:.4g}{}{}, delay {:.0f} ms\n",
                   path, sel.outputs[static_cast<std::size_t>(i)], c.fit[i], c.correlation[i],
                   c.rmse[i], o.unit.empty() ? "" : " ", o.unit, 1000.0 * c.delay[i]);
      }
      fit_sum += c.mean_fit();
      rmse_sum += c.mean_rmse();
    }
    if (!plot_path.empty()) {
      plot(plot_path, results, sel.outputs);
      fmt::print("plot written to {}\n", plot_path);
    }
    const auto files_count = static_cast<double>(logs.size());
    const std::string unit = model.outputs.front().unit;
    fmt::print("mean RMSE: {:.4g}{}{}\n", rmse_sum / files_count, unit.empty() ? "" : " ", unit);
    fmt::print("mean fit: {:.2f}%\n", fit_sum / files_count);
    wf::require_written(stdout, "standard output");
  } catch (const std::exception& e) {
    fmt::print(stderr, "endohaptics-replay: error: {}\n", e.what());
    return 1;
  }
  return 0;
}
