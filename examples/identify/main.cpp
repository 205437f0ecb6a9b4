// endohaptics-identify: identifies a force model from logs (worksheet 4.2): reads each log and
// prints what the reader dropped, resamples to --ts, low-pass/offset as 4.2.1 for the fit,
// identifies with N4SID/MOESP/CVA (or all three), optionally with input dead zones, and chooses
// method, dead zones and order by the causal score (x0 from the inputs, warm-up excluded, inputs
// filtered forward only, output as logged), refusing unstable and near-integrating models.
// Joint force models (--method stall_hold, push_load_observer, bidirectional_load_observer:
// workflow/joint_models.hpp) are further families; with several, the family is chosen by an inner
// cross-validation on the training files (workflow::choose_family). Each format has recommended
// defaults (workflow/format_defaults.hpp). Writes a JSON model. Workflow:
// endohaptics/workflow/workflow.hpp; results: docs/identification_results.md.
#include <fmt/format.h>
#include <algorithm>

#include <CLI/CLI.hpp>
#include <cmath>
#include <cstdio>
#include <endohaptics/workflow/command_line.hpp>
#include <endohaptics/workflow/format_defaults.hpp>
#include <endohaptics/workflow/workflow.hpp>
#include <exception>
#include <optional>
#include <string>
#include <string_view>
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
  std::string offset = "none", input_offset = "none", x0 = "steady", out_path;
  double ts = 0.0;
  int max_order = 10;
  wf::Preprocessing pre;
  wf::ScoringOptions scoring;
  double max_time_constant = 0.0;
  bool drop_non_finite = false;
  app.add_option("--log", logs, "log file (repeat for several experiments)")->required();
  app.add_option("--format", format,
                 "endowrist-2016, umn-mis-2018 or csv (header line names the columns); sets the "
                 "recommended defaults of the options marked [format]")
      ->capture_default_str();
  app.add_option("--input", inputs, "input signal (repeat) [format]");
  app.add_option("--output", outputs, "output signal (repeat) [format]");
  auto* order_opt = app.add_option("--order", order,
                                   "model order N, or auto (select_order, then every order "
                                   "1..max-order by the causal score) [format]")
                        ->check(number_in(1, limits::max_order, {"auto"}));
  app.add_option("--max-order", max_order, "largest order --order auto considers")
      ->check(number_in(1, limits::max_order))
      ->capture_default_str();
  auto* method_opt = app.add_option(
      "--method", method,
      "n4sid, moesp, cva, best (all three, highest causal score), static, stall_hold, "
      "push_load_observer or bidirectional_load_observer, or a comma list of them (every family "
      "fitted, the best by an inner "
      "cross-validation on the training files chosen) [format]");
  auto* deadzone_opt = app.add_option(
      "--deadzone", deadzone,
      "input dead zone: auto, none or half width (or one per input, comma-separated) [format]");
  auto* ts_opt = app.add_option("--ts", ts,
                                "resampling period, s (csv without time column: the row time, "
                                "default 1; else [format] or the median step of the first log)")
                     ->check(number_in(limits::min_sample_time, limits::max_sample_time));
  auto* lowpass_opt =
      app.add_option("--lowpass", pre.cutoff,
                     "Butterworth low-pass cutoff, Hz (0: none): zero-phase on the fit data, "
                     "forward only on the scoring data and in replay [format]")
          ->check(number_in(0.0, limits::max_cutoff));
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
  app.add_option("--x0", x0,
                 "initial state for the causal score: steady (first input sample) or zero")
      ->capture_default_str();
  app.add_option("--warmup", scoring.warmup,
                 "s at the start of each segment left out of the score (inputs only set the state)")
      ->check(number_in(0.0, wf::max_warmup))
      ->capture_default_str();
  auto* max_tc_opt =
      app.add_option("--max-time-constant", max_time_constant,
                     "s; models with a slower mode are refused as near-integrating, as are those "
                     "slower than the longest segment [format: 2 for endowrist-2016 and "
                     "umn-mis-2018, none for csv]")
          ->check(number_in(1e-6, 1e6));
  app.add_option("--out", out_path, "write the model here (JSON)");
  CLI11_PARSE(app, argc, argv);

  try {
    wf::LogSelection sel;
    sel.format = files::parse_log_format(format);
    sel.drop_non_finite = drop_non_finite;
    const wf::FormatDefaults defaults = wf::format_defaults(sel.format);
    sel.inputs = !inputs.empty() ? inputs : defaults.inputs;
    sel.outputs = !outputs.empty() ? outputs : defaults.outputs;
    if (sel.inputs.empty() || sel.outputs.empty()) {
      throw endohaptics::Error("--format csv needs --input and --output column names");
    }
    if (lowpass_opt->count() == 0) pre.cutoff = defaults.preprocessing.cutoff;
    if (method_opt->count() == 0) method = defaults.method;
    if (order_opt->count() == 0) order = defaults.order;
    if (deadzone_opt->count() == 0) deadzone = wf::default_deadzone(defaults, sel.inputs);
    if (ts_opt->count() == 0 && defaults.sample_time > 0.0) ts = defaults.sample_time;
    pre.output_offset = wf::offset_mode_from_string(offset);
    pre.input_offset = wf::offset_mode_from_string(input_offset);
    wf::WorkflowOptions options;
    options.max_order = max_order;
    options.max_time_constant =
        max_tc_opt->count() > 0 ? max_time_constant : defaults.max_time_constant;
    if (order != "auto") options.order = wf::parse_number(order, "--order", 1, limits::max_order);
    // A comma list: n4sid, moesp, cva, best (= the three) and static, all scored alike.
    options.candidates.clear();
    std::vector<files::ModelKind> joint_kinds;
    for (std::string_view m : wf::detail::split(method, ',')) {
      if (const auto kind = wf::joint_model_kind(m)) {
        joint_kinds.push_back(*kind);
      } else if (m == "best") {
        for (const auto w : {id::Weighting::n4sid, id::Weighting::moesp, id::Weighting::cva}) {
          options.candidates.push_back(w);
        }
      } else if (m == "static") {
        options.static_gain = true;
      } else {
        options.candidates.push_back(id::weighting_from_string(m));
      }
    }
    options.deadzone = wf::parse_deadzone(deadzone, sel.inputs.size());
    // The joint models take (current, velocity) -> one output; from the format's defaults they
    // are left out (with a note) for other signal lists, asked for by --method they are an error.
    // (the observers: or 3, the current command third).
    const auto joint_inputs_ok = [&] {
      const bool stall = std::find(joint_kinds.begin(), joint_kinds.end(),
                                   files::ModelKind::stall_hold) != joint_kinds.end();
      return sel.outputs.size() == 1 && sel.inputs.size() >= 2 &&
             sel.inputs.size() <= (stall ? 2U : 3U);
    };
    if (!joint_kinds.empty() && !joint_inputs_ok()) {
      if (method_opt->count() > 0) {
        throw endohaptics::Error(
            "--method " + method +
            ": joint models need 1 output and the inputs (current, velocity): stall_hold "
            "those 2, push_load_observer and bidirectional_load_observer 2 or 3 (current, "
            "velocity, current command)");
      }
      fmt::print(
          "note: the format's joint models ({}) need 2 inputs (current, velocity; "
          "the observers: a third, the current command, optional) and 1 output: not "
          "fitted\n",
          method);
      joint_kinds.clear();
    }
    const bool subspace_family = !options.candidates.empty() || options.static_gain;
    scoring.initial_state = wf::initial_state_from_string(x0);
    if (!wf::is_causal(scoring.initial_state) ||
        scoring.initial_state == wf::InitialStateMode::stored) {
      throw endohaptics::Error(
          "--x0 must be steady or zero here: identify chooses by the causal "
          "score (the oracle score of the chosen model is printed too)");
    }
    options.scoring = scoring;

    // Sample time: given, else the format's, else the median step of the first log (a CSV
    // without time column: its row time, 1 s unless --ts says otherwise).
    const bool ts_given = ts_opt->count() > 0;
    sel.csv_row_time = ts_given ? ts : 1.0;
    if (!(ts > 0.0)) ts = wf::default_sample_time(logs.front(), sel);
    // The joint models' grid: given --ts, else the format's, else the subspace grid; no
    // low-pass beyond their own filters.
    const double joint_ts =
        ts_given || !(defaults.joint_sample_time > 0.0) ? ts : defaults.joint_sample_time;
    wf::Preprocessing joint_pre = pre;
    joint_pre.cutoff = 0.0;
    joint_pre.output_offset = wf::OffsetMode::none;
    joint_pre.input_offset = wf::OffsetMode::none;
    joint_pre.detrend = false;
    std::vector<wf::PreparedLog> prepared, scored, joint;
    for (const auto& path : logs) {
      if (subspace_family) {
        prepared.push_back(wf::prepare_log(path, sel, ts, pre));
        scored.push_back(wf::prepare_log(path, sel, ts, pre, 20, wf::Preparation::score));
        fmt::print("{}", wf::summary(prepared.back()));
      }
      if (!joint_kinds.empty()) {
        joint.push_back(
            wf::prepare_log(path, sel, joint_ts, joint_pre, 20, wf::Preparation::score));
        if (!subspace_family || joint_ts != ts) fmt::print("{}", wf::summary(joint.back()));
      }
    }
    fmt::print("preprocessing for the fit: {}\n", wf::describe(pre));
    const wf::TimeConstantLimit tc_limit =
        wf::time_constant_limit(options.max_time_constant, prepared);
    fmt::print(
        "scoring (causal): x0 {}, warm-up {} s per segment excluded, inputs held and low-passed "
        "forward only ({} Hz), output as logged (no offset, filter or detrend); refused: "
        "spectral radius >= 1 or slowest time constant > {}\n",
        x0, scoring.warmup, pre.cutoff,
        std::isfinite(tc_limit.seconds)
            ? fmt::format("{} s{}", tc_limit.seconds,
                          tc_limit.source.empty() ? "" : " (" + tc_limit.source + ")")
            : std::string("(no limit)"));

    auto units = [&](const std::vector<std::string>& names) {
      std::vector<files::SignalInfo> info;
      const files::Log first = files::read_log(logs.front(), sel.format);
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
    std::optional<wf::WorkflowResult> subspace;
    if (subspace_family && joint_kinds.empty()) {
      subspace = wf::identify_logs(prepared, scored, in_info, out_info, options);
    } else if (subspace_family) {
      // With joint models to fall back on, a subspace family that cannot be fitted (every
      // candidate refused) is reported and left out, not fatal.
      try {
        subspace = wf::identify_logs(prepared, scored, in_info, out_info, options);
      } catch (const endohaptics::Error& e) {
        fmt::print("subspace family left out: {}\n", e.what());
      }
    }
    const wf::WorkflowResult empty_result{};
    const wf::WorkflowResult& result = subspace ? *subspace : empty_result;

    for (const wf::CandidateModel& c : result.candidates) {
      if (!c.method.starts_with("static")) {
        const auto& sv = c.linear.order_singular_values;
        std::string line;
        for (Eigen::Index i = 0; i < std::min<Eigen::Index>(sv.size(), max_order + 5); ++i) {
          line += fmt::format(" {:.4g}", sv[i]);
        }
        fmt::print("{}: Hankel singular values (MOESP, {} block rows):{}\n", c.method,
                   c.linear.block_rows, line);
        fmt::print("{}: order {} ({}), spectral radius {:.5f}, slowest time constant {:.3g} s{}\n",
                   c.method, c.linear.order,
                   c.order_searched     ? "order search"
                   : options.order == 0 ? "automatic"
                                        : "given",
                   c.spectral_radius, c.time_constant,
                   c.refused.empty() ? std::string() : " REFUSED: " + c.refused);
      }
      for (std::size_t j = 0; j < c.model.input_nonlinearity.size(); ++j) {
        const auto& m = c.model.input_nonlinearity[j];
        if (m.kind == endohaptics::model::StaticMapKind::none) continue;
        fmt::print("{}: input {} dead zone [{:.4g}, {:.4g}]\n", c.method, sel.inputs[j], m.lower,
                   m.upper);
      }
      fmt::print("{}: mean causal fit {:.2f} %\n", c.method, c.mean_fit);
    }
    for (const wf::OrderTrial& t : result.order_search) {
      fmt::print("order search: order {} mean causal fit {:.2f} %, spectral radius {:.5f}{}\n",
                 t.order, t.mean_fit, t.spectral_radius,
                 t.refused.empty() ? std::string() : " REFUSED: " + t.refused);
    }
    fmt::print("models fitted and scored: {}\n", result.evaluations);
    for (const std::string& f : result.failures) fmt::print("failed: {}\n", f);
    if (subspace) {
      const wf::CandidateModel& best = result.chosen();
      if (!best.method.starts_with("static") && (best.linear.input_scale.array() != 1.0).any()) {
        fmt::print(
            "scaling: each column divided by its RMS for the fit (inputs {:.4g}, outputs "
            "{:.4g}); the model is in the logs' units\n",
            fmt::join(best.linear.input_scale.begin(), best.linear.input_scale.end(), " "),
            fmt::join(best.linear.output_scale.begin(), best.linear.output_scale.end(), " "));
      }
      fmt::print(
          "subspace family: {} (order {}, spectral radius {:.5f}), mean causal fit {:.2f} %\n",
          best.method, best.model.state_space.state_size(), best.spectral_radius, best.mean_fit);
    }
    // The family: by the inner cross-validation on the training files when there are several.
    const wf::ModelChoice choice =
        wf::choose_family(subspace ? &*subspace : nullptr, joint_kinds, prepared, scored, joint,
                          in_info, out_info, options);
    if (choice.families.size() > 1) {
      fmt::print(
          "family choice ({}): causal score of each family fitted on the other training files"
          "{}\n",
          choice.folds.empty()
              ? "one training file: the training score"
              : fmt::format("inner cross-validation, {} folds", choice.folds.size()),
          subspace ? " (the subspace family refitted with its structure chosen on all of them)"
                   : "");
      for (const wf::FamilyScore& f : choice.families) {
        fmt::print(
            "family {}: mean causal fit {:.2f} %, mean RMSE {:.4g} {} (per fold: {:.1f}){}\n",
            f.family, f.mean_fit, f.mean_rmse, out_info.front().unit, fmt::join(f.fold_fit, " "),
            f.failure.empty() ? std::string() : " FAILED on a fold: " + f.failure);
      }
    }
    const bool joint_chosen = choice.model.is_joint_model();
    fmt::print("chosen: {}{}\n", choice.family,
               choice.families.size() > 1 ? " (the highest mean causal fit of the families above)"
               : joint_chosen             ? " (the only family asked for)"
                                          : "");
    if (joint_chosen) {
      fmt::print(
          "{}\nits grid: Ts {} s, inputs {} (current) and {} (velocity){}, no low-pass "
          "beyond its own filters; the state starts from the model's reset (filters at the "
          "first sample)\n",
          choice.joint_summary, choice.model.state_space.sample_time(), sel.inputs[0],
          sel.inputs[1],
          sel.inputs.size() > 2 ? " and " + sel.inputs[2] + " (the current command)"
                                : std::string());
    } else {
      fmt::print("chosen model: order {}, spectral radius {:.5f}\n",
                 choice.model.state_space.state_size(), result.chosen().spectral_radius);
    }
    double rmse_sum = 0.0, fit_sum = 0.0;
    for (std::size_t k = 0; k < choice.files.size(); ++k) {
      const wf::FileComparison& f = choice.files[k];
      // The old, output-fitted score beside the causal one, labelled (linear models only).
      std::string oracle_text = "no oracle score: a joint model has no linear state";
      wf::FileComparison oracle;
      if (!joint_chosen) {
        oracle = wf::compare_log(choice.model, prepared[k],
                                 {wf::InitialStateMode::oracle, 0.0, scoring.max_lag});
      }
      for (Eigen::Index i = 0; i < f.fit.size(); ++i) {
        if (!joint_chosen) {
          oracle_text = fmt::format("oracle x0, zero-phase data: {:.2f} %", oracle.fit[i]);
        }
        fmt::print(
            "fit {}: {} causal {:.2f} %, correlation {:.4f}, RMSE {:.4g} {}, delay {:.0f} ms "
            "({})\n",
            f.source, sel.outputs[static_cast<std::size_t>(i)], f.fit[i], f.correlation[i],
            f.rmse[i], out_info[static_cast<std::size_t>(i)].unit, 1000.0 * f.delay[i],
            oracle_text);
      }
      rmse_sum += f.mean_rmse();
      fit_sum += f.mean_fit();
    }
    // No false success: a fit that is not finite (a diverging model, a constant output) fails.
    for (const wf::FileComparison& f : choice.files) wf::require_finite_scores(f, sel.outputs);
    const auto n_files = static_cast<double>(choice.files.size());
    const std::string& unit = out_info.front().unit;
    fmt::print("mean RMSE: {:.4g}{}{}\n", rmse_sum / n_files, unit.empty() ? "" : " ", unit);
    fmt::print("mean fit: {:.2f}%\n", fit_sum / n_files);
    if (!out_path.empty()) {
      files::ModelFile model = choice.model;
      model.provenance.notes =
          "preprocessing: " + wf::describe(joint_chosen ? joint_pre : pre) +
          "\nfit_percent: mean causal fit over the identification logs, " +
          (joint_chosen ? std::string("state from the model's reset") : "x0 " + x0) + ", warm-up " +
          fmt::format("{}", scoring.warmup) + " s\nchosen: " + choice.family +
          (choice.families.size() > 1 ? " by inner cross-validation on the training files" : "") +
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
