//! @file
//! Function bodies of workflow/identify_request.hpp: included at its end (header-only, the
//! default), or compiled once with ENDOHAPTICS_SEPARATE_COMPILATION
//! (core/separate_compilation.hpp).
#pragma once

#include "endohaptics/model/stop_operators.hpp"
#include "endohaptics/workflow/identify_request.hpp"

namespace endohaptics::workflow {

ENDOHAPTICS_DECL const WorkflowResult& IdentifyProgress::subspace_result() const {
  static const WorkflowResult empty{};
  return subspace ? *subspace : empty;
}

namespace detail {

//! Names and units of `names` as the first log gives them.
inline std::vector<files::SignalInfo> signal_info(const files::Log& first,
                                                  const std::vector<std::string>& names) {
  std::vector<files::SignalInfo> info;
  for (const auto& n : names) {
    std::string unit;
    for (std::size_t i = 0; i < first.names.size(); ++i) {
      if (first.names[i] == n) unit = first.units[i];
    }
    info.push_back({n, unit});
  }
  return info;
}

//! The request resolved against the format's defaults: selection, options, methods, grids.
inline void resolve(IdentifyProgress& r, const IdentifyHooks& hooks) {
  const IdentifyRequest& q = r.request;
  r.selection.format = files::parse_log_format(q.format);
  r.selection.drop_non_finite = q.drop_non_finite;
  const FormatDefaults defaults = format_defaults(r.selection.format);
  r.selection.inputs = !q.inputs.empty() ? q.inputs : defaults.inputs;
  r.selection.outputs = !q.outputs.empty() ? q.outputs : defaults.outputs;
  if (r.selection.inputs.empty() || r.selection.outputs.empty()) {
    ENDOHAPTICS_THROW(Error("--format csv needs --input and --output column names"));
  }
  const std::vector<std::string>& inputs = r.selection.inputs;
  r.preprocessing = q.preprocessing;
  r.preprocessing.cutoff = q.lowpass ? *q.lowpass : defaults.preprocessing.cutoff;
  r.method = q.method ? *q.method : defaults.method;
  const std::string order = q.order ? *q.order : defaults.order;
  const std::string deadzone = q.deadzone ? *q.deadzone : default_deadzone(defaults, inputs);
  double ts = q.sample_time ? *q.sample_time : defaults.sample_time;
  r.preprocessing.output_offset = offset_mode_from_string(q.offset);
  r.preprocessing.input_offset = offset_mode_from_string(q.input_offset);
  WorkflowOptions& options = r.options;
  options.max_order = q.max_order;
  options.nested_joint_constants = q.nested_joint_constants;
  options.max_time_constant =
      q.max_time_constant ? *q.max_time_constant : defaults.max_time_constant;
  if (order != "auto") options.order = parse_number(order, "--order", 1, limits::max_order);
  // The subspace weightings and the static baseline are scored alike; the joint models are
  // families of their own.
  options.candidates.clear();
  for (const Method m : parse_methods(r.method)) {
    if (const auto kind = joint_kind_of(m)) {
      r.joint_kinds.push_back(*kind);
    } else if (const auto w = weighting_of(m)) {
      options.candidates.push_back(*w);
    } else {
      options.static_gain = true;
    }
  }
  options.deadzone = parse_deadzone(deadzone, inputs.size());
  // The joint models take (current, velocity) -> one output (the observers: or 3, the current
  // command third); from the format's defaults they are left out (with a note) for other signal
  // lists, asked for by --method they are an error.
  const bool stall = std::find(r.joint_kinds.begin(), r.joint_kinds.end(),
                               files::ModelKind::stall_hold) != r.joint_kinds.end();
  const bool joint_inputs_ok =
      r.selection.outputs.size() == 1 && inputs.size() >= 2 && inputs.size() <= (stall ? 2U : 3U);
  if (!r.joint_kinds.empty() && !joint_inputs_ok) {
    if (q.method) {
      ENDOHAPTICS_THROW(
          Error("--method " + r.method +
                ": joint models need 1 output and the inputs (current, velocity): stall_hold "
                "those 2, push_load_observer and bidirectional_load_observer 2 or 3 (current, "
                "velocity, current command)"));
    }
    if (hooks.text) {
      hooks.text("note: the format's joint models (" + r.method +
                 ") need 2 inputs (current, velocity; the observers: a third, the current "
                 "command, optional) and 1 output: not fitted\n");
    }
    r.joint_kinds.clear();
  }
  r.subspace_family = !options.candidates.empty() || options.static_gain;
  options.scoring.warmup = q.warmup;
  options.scoring.initial_state = initial_state_from_string(q.x0);
  if (!is_causal(options.scoring.initial_state) ||
      options.scoring.initial_state == InitialStateMode::stored) {
    ENDOHAPTICS_THROW(
        Error("--x0 must be steady or zero here: identify chooses by the causal "
              "score (the oracle score of the chosen model is printed too)"));
  }
  // Sample time: given, else the format's, else the median step of the first log (a CSV
  // without time column: its row time, 1 s unless --ts says otherwise).
  r.selection.csv_row_time = q.sample_time ? *q.sample_time : 1.0;
  if (!(ts > 0.0)) ts = default_sample_time(q.logs.front(), r.selection);
  r.sample_time = ts;
  // The joint models' grid: given --ts, else the format's, else the subspace grid; no low-pass
  // beyond their own filters.
  r.joint_sample_time =
      q.sample_time || !(defaults.joint_sample_time > 0.0) ? ts : defaults.joint_sample_time;
  r.joint_preprocessing = r.preprocessing;
  r.joint_preprocessing.cutoff = 0.0;
  r.joint_preprocessing.output_offset = OffsetMode::none;
  r.joint_preprocessing.input_offset = OffsetMode::none;
  r.joint_preprocessing.detrend = false;
}

}  // namespace detail

ENDOHAPTICS_DECL IdentifyReport run_identify(const IdentifyRequest& request,
                                             const IdentifyHooks& hooks) {
  if (request.logs.empty()) ENDOHAPTICS_THROW(Error("identify: no --log given"));
  IdentifyProgress r;
  r.request = request;
  detail::resolve(r, hooks);
  const auto say = [&](const std::string& text) {
    if (hooks.text) hooks.text(text);
  };
  for (const auto& path : request.logs) {
    if (r.subspace_family) {
      r.fit_logs.push_back(prepare_log(path, r.selection, r.sample_time, r.preprocessing));
      r.score_logs.push_back(
          prepare_log(path, r.selection, r.sample_time, r.preprocessing, 20, Preparation::score));
      say(summary(r.fit_logs.back()));
    }
    if (!r.joint_kinds.empty()) {
      r.joint_logs.push_back(prepare_log(path, r.selection, r.joint_sample_time,
                                         r.joint_preprocessing, 20, Preparation::score));
      if (!r.subspace_family || r.joint_sample_time != r.sample_time) {
        say(summary(r.joint_logs.back()));
      }
    }
  }
  // The play on input 0: the subspace family is fitted and scored on the played input; the model
  // file carries the width (set below, after every score), and replay and the bridge apply it.
  model::check_friction_play(request.current_play, request.current_play_slide,
                             request.current_play_viscous, "",
                             {"--current-play", "--current-play-slide", "--current-play-viscous"});
  if (request.current_play > 0.0 && !r.subspace_family) {
    ENDOHAPTICS_THROW(
        Error("--current-play: the method list has no subspace family, the only "
              "one whose input the play is (the joint models hold their own "
              "friction)"));
  }
  const double slide = model::friction_play_slide(request.current_play, request.current_play_slide);
  if (request.current_play > 0.0) {
    for (auto* logs : {&r.fit_logs, &r.score_logs}) {
      for (PreparedLog& log : *logs) {
        for (DataSet& d : log.segments) {
          d.u = identification::played_input(d.u, request.current_play, slide,
                                             request.current_play_viscous);
        }
      }
    }
  }
  r.time_constant_limit = time_constant_limit(r.options.max_time_constant, r.fit_logs);
  r.options.progress = hooks.progress;
  if (hooks.prepared) hooks.prepared(r);

  const files::Log first = files::read_log(request.logs.front(), r.selection.format);
  r.input_info = detail::signal_info(first, r.selection.inputs);
  r.output_info = detail::signal_info(first, r.selection.outputs);
  if (r.subspace_family && r.joint_kinds.empty()) {
    r.subspace = identify_logs(r.fit_logs, r.score_logs, r.input_info, r.output_info, r.options);
  } else if (r.subspace_family) {
    // With joint models to fall back on, a subspace family that cannot be fitted (every
    // candidate refused) is reported and left out, not fatal.
#if defined(__cpp_exceptions)
    try {
#endif
      r.subspace = identify_logs(r.fit_logs, r.score_logs, r.input_info, r.output_info, r.options);
#if defined(__cpp_exceptions)
    } catch (const Error& e) {
      r.subspace_left_out = e.what();
    }
#endif
  }
  if (hooks.subspace_fitted) hooks.subspace_fitted(r);

  // The family: by the inner cross-validation on the training files when there are several.
  ModelChoice choice =
      choose_family(r.subspace ? &*r.subspace : nullptr, r.joint_kinds, r.fit_logs, r.score_logs,
                    r.joint_logs, r.input_info, r.output_info, r.options);
  if (request.free_threshold && *request.free_threshold != "none") {
    if (choice.model.is_joint_model()) {
      ENDOHAPTICS_THROW(Error("--free-threshold: the chosen family (" + choice.family +
                              ") is a joint model, which holds its own free-motion behaviour; "
                              "give it for a subspace family only"));
    }
    choice.model.free_motion_threshold =
        *request.free_threshold == "auto"
            ? free_motion_threshold_of(choice.files)
            : parse_number(*request.free_threshold, "--free-threshold", 0.0,
                           files::ModelFile::max_parameter);
    // The scores of the model as it now runs (replay and the bridge apply the threshold).
    double sum = 0.0;
    for (std::size_t k = 0; k < choice.files.size(); ++k) {
      choice.files[k] = compare_log(choice.model, r.score_logs[k], r.options.scoring);
      sum += choice.files[k].mean_fit();
    }
    choice.model.provenance.fit_percent = {sum / static_cast<double>(choice.files.size())};
  }
  // The play is the subspace family's input operator: the joint models meet it in the family
  // choice on their own inputs (they hold their own friction), and one of them chosen is written
  // without it.
  files::ModelFile model = choice.model;
  IdentifyReport report{std::move(r), std::move(choice), {}, 0.0, 0.0, std::move(model)};
  const bool joint = report.joint_chosen();
  double rmse_sum = 0.0, fit_sum = 0.0;
  for (std::size_t k = 0; k < report.choice.files.size(); ++k) {
    // The old, output-fitted score beside the causal one (linear models only).
    if (!joint) {
      report.oracle.push_back(
          compare_log(report.choice.model, report.fit_logs[k],
                      {InitialStateMode::oracle, 0.0, report.options.scoring.max_lag}));
    }
    rmse_sum += report.choice.files[k].mean_rmse();
    fit_sum += report.choice.files[k].mean_fit();
  }
  const auto n_files = static_cast<double>(report.choice.files.size());
  report.mean_rmse = rmse_sum / n_files;
  report.mean_fit = fit_sum / n_files;
  // Every score above ran on the played input; from here the model plays its input itself.
  report.model.current_play = joint ? 0.0 : request.current_play;
  if (!joint) {
    report.model.current_play_slide = request.current_play_slide;
    report.model.current_play_viscous = request.current_play_viscous;
  }
  report.model.provenance.notes =
      "preprocessing: " + describe(joint ? report.joint_preprocessing : report.preprocessing) +
      "\nfit_percent: mean causal fit over the identification logs, " +
      (joint ? std::string("state from the model's reset") : "x0 " + request.x0) + ", warm-up " +
      detail::format_number(request.warmup) + " s\nchosen: " + report.choice.family +
      (report.choice.families.size() > 1 ? " by inner cross-validation on the training files"
                                         : "") +
      "\ntool: endohaptics-identify";
  return report;
}

ENDOHAPTICS_DECL double free_motion_threshold_of(const std::vector<FileComparison>& files) {
  std::vector<double> free;
  std::size_t scored = 0;
  for (const FileComparison& f : files) {
    for (std::size_t s = 0; s < f.y.size(); ++s) {
      const Eigen::MatrixXd& y = f.y[s];
      const Eigen::MatrixXd& y_hat = f.y_hat[s];
      const Eigen::Index skip = std::min(f.warmup_samples, y.rows() - 1);
      for (Eigen::Index i = skip; i < y.rows(); ++i) {
        for (Eigen::Index o = 0; o < y.cols(); ++o) {
          ++scored;
          if (y(i, o) == 0.0 && std::isfinite(y_hat(i, o))) free.push_back(std::abs(y_hat(i, o)));
        }
      }
    }
  }
  if (free.size() < 100) {
    ENDOHAPTICS_THROW(
        Error("--free-threshold auto: the training logs hold " + std::to_string(free.size()) +
              " scored samples whose true output is exactly 0 (of " + std::to_string(scored) +
              "; at least 100 needed): record phases where nothing touches, or give "
              "the threshold as a value"));
  }
  const auto at = static_cast<std::ptrdiff_t>(
      std::min(free.size() - 1, static_cast<std::size_t>(0.99 * static_cast<double>(free.size()))));
  std::nth_element(free.begin(), free.begin() + at, free.end());
  return free[static_cast<std::size_t>(at)];
}

ENDOHAPTICS_DECL void check_scores(const IdentifyReport& report) {
  for (const FileComparison& f : report.choice.files) {
    require_finite_scores(f, report.selection.outputs);
  }
}

}  // namespace endohaptics::workflow
