//! @file
//! Function bodies of workflow/replay_request.hpp: included at its end (header-only, the
//! default), or compiled once with ENDOHAPTICS_SEPARATE_COMPILATION
//! (core/separate_compilation.hpp).
#pragma once

#include "endohaptics/workflow/option_parsing.hpp"
#include "endohaptics/workflow/preset_models.hpp"
#include "endohaptics/workflow/replay_request.hpp"

namespace endohaptics::workflow {

namespace detail {

//! "a, b, c".
inline std::string comma_list(const std::vector<std::string>& names) {
  std::string out;
  for (const auto& n : names) out += (out.empty() ? "" : ", ") + n;
  return out;
}

}  // namespace detail

ENDOHAPTICS_DECL ReplayReport run_replay(const ReplayRequest& q, const ReplayHooks& hooks) {
  const bool preset = q.model.starts_with("preset:");
  ReplayReport r{.request = q,
                 .model = preset ? preset_model(q.model.substr(7)) : files::load_model(q.model),
                 .name = preset ? q.model : "model " + q.model};
  for (const auto& s : r.model.inputs) r.model_inputs.push_back(s.name);
  for (const auto& s : r.model.outputs) r.model_outputs.push_back(s.name);
  LogSelection& sel = r.selection;
  sel.format = files::parse_log_format(q.format);
  sel.drop_non_finite = q.drop_non_finite;
  sel.inputs = q.inputs.empty() ? r.model_inputs : q.inputs;
  sel.outputs = q.outputs.empty() ? r.model_outputs : q.outputs;
  if (sel.inputs.size() != r.model_inputs.size() || sel.outputs.size() != r.model_outputs.size()) {
    ENDOHAPTICS_THROW(Error(
        r.name + " has " + std::to_string(r.model_inputs.size()) + " input(s) (" +
        detail::comma_list(r.model_inputs) + ") and " + std::to_string(r.model_outputs.size()) +
        " output(s) (" + detail::comma_list(r.model_outputs) + "); the command line names " +
        std::to_string(sel.inputs.size()) + " and " + std::to_string(sel.outputs.size())));
  }
  sel.csv_row_time = q.csv_row_time ? *q.csv_row_time : r.model.state_space.sample_time();

  // Overrides given win over the recorded preprocessing.
  Preprocessing& pre = r.preprocessing;
  const auto recorded = recorded_preprocessing(r.model);
  r.recorded = recorded.has_value();
  if (recorded) pre = *recorded;
  if (q.lowpass) pre.cutoff = *q.lowpass;
  if (q.filter_order) pre.filter_order = *q.filter_order;
  if (q.offset_window) pre.offset_duration = *q.offset_window;
  if (q.detrend) pre.detrend = *q.detrend;
  if (q.max_gap) pre.max_gap = *q.max_gap;
  if (q.min_segment) pre.min_segment = *q.min_segment;
  if (q.offset) pre.output_offset = offset_mode_from_string(*q.offset);
  if (q.input_offset) pre.input_offset = offset_mode_from_string(*q.input_offset);
  r.scoring.warmup = q.warmup;
  r.scoring.initial_state = initial_state_from_string(q.x0);
  // A clamp preset runs as the bridge runs it (one definition: estimation/clamp_presets.hpp).
  if (preset) r.scoring.clamp_preset = replayed_clamp_preset(q.model.substr(7));
  const bool causal = r.causal();
  if (causal && (q.offset || q.input_offset || q.detrend)) {
    ENDOHAPTICS_THROW(
        Error("--offset, --input-offset and --detrend look at the whole file (or the output): they "
              "apply only to the output-fitted --x0 oracle score; the causal score compares the "
              "output as logged"));
  }
  if (r.scoring.clamp_preset && !causal) {
    ENDOHAPTICS_THROW(
        Error("--x0 oracle: " + r.name +
              " runs as the bridge runs it (its dead zone, gate and saturation), from its reset "
              "state: it has no linear state to fit to the output; replay scores it causally "
              "(leave out --x0)"));
  }
  if (r.model.is_joint_model() && !causal) {
    ENDOHAPTICS_THROW(
        Error("--x0 oracle: " + r.name + " is a " + std::string(files::to_string(r.model.kind())) +
              " model: it has no linear state to fit to the output (it starts from its reset "
              "state, filters at the first sample); replay scores it causally (leave out --x0)"));
  }
  if (!causal) r.scoring.warmup = 0.0;  // MATLAB compare: every sample
  if (hooks.resolved) hooks.resolved(r);

  double fit_sum = 0.0, rmse_sum = 0.0;
  for (const auto& path : q.logs) {
    const PreparedLog log = prepare_log(path, sel, r.model.state_space.sample_time(), pre, 20,
                                        causal ? Preparation::score : Preparation::fit);
    if (hooks.prepared) hooks.prepared(log);
    r.files.push_back(compare_log(r.model, log, r.scoring));
    const FileComparison& c = r.files.back();
    // No false success: a diverging model or an undefined score fails the run.
    require_finite_scores(c, sel.outputs);
    if (hooks.scored) hooks.scored(r, c);
    fit_sum += c.mean_fit();
    rmse_sum += c.mean_rmse();
  }
  const auto n_files = static_cast<double>(q.logs.size());
  r.mean_rmse = rmse_sum / n_files;
  r.mean_fit = fit_sum / n_files;
  return r;
}

}  // namespace endohaptics::workflow
