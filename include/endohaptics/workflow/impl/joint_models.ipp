//! @file
//! Function bodies of workflow/joint_models.hpp: included at its end (header-only, the default),
//! or compiled once with ENDOHAPTICS_SEPARATE_COMPILATION (core/separate_compilation.hpp).
#pragma once

#include "endohaptics/workflow/joint_models.hpp"

namespace endohaptics::workflow {

ENDOHAPTICS_DECL std::optional<files::ModelKind> joint_model_kind(std::string_view method) {
  for (const MethodName& m : method_names) {  // the one table of method names
    if (m.name == method) return joint_kind_of(m.method);
  }
  return std::nullopt;
}

namespace detail {

// A segment as the observers see it: the current, the encoder angle as the running sum
// of the velocity (column 1) times `ts` (up to a constant: the observer uses only increments),
// the load `y` (may be empty when only simulating) and, with a third column, the command.
inline LoadObserverData load_observer_data(const Eigen::MatrixXd& u, Eigen::VectorXd y, double ts) {
  LoadObserverData e{u.col(0), Eigen::VectorXd(u.rows()), std::move(y),
                     u.cols() > 2 ? Eigen::VectorXd(u.col(2)) : Eigen::VectorXd()};
  double position = 0.0;
  for (Eigen::Index k = 0; k < u.rows(); ++k) {
    position += u(k, 1) * ts;
    e.position[k] = position;
  }
  return e;
}

}  // namespace detail

ENDOHAPTICS_DECL Eigen::VectorXd simulate_joint_model(const files::ModelFile& model,
                                                      const Eigen::MatrixXd& u) {
  if (!model.is_joint_model()) {
    detail::fail("simulate_joint_model: the model file is of kind \"" +
                 std::string(files::to_string(model.kind())) + "\", not a joint model");
  }
  const std::optional<files::CurrentReference>& reference = model.current_reference;
  if (u.cols() != (reference ? 3 : 2)) {
    detail::fail("simulate_joint_model: " + std::to_string(u.cols()) +
                 " input columns, the model " +
                 (reference ? "takes 3 (current, velocity, current command)"
                            : "takes 2 (current, velocity)"));
  }
  if (const auto* p = std::get_if<estimation::StallHoldParameters<double>>(&model.parameters)) {
    estimation::StallHold<double> m(*p);
    Eigen::VectorXd y(u.rows());
    const estimation::SimulationResult r = estimation::simulate(
        m,
        [&](Eigen::Index k) noexcept {
          return estimation::JointSignals<double>{0.0, u(k, 1), u(k, 0), 0.0};
        },
        y);
    if (!r.ok()) {
      detail::fail("simulate_joint_model: stall_hold: non-finite signal or result at sample " +
                   std::to_string(r.sample));
    }
    return y;
  }
  const LoadObserverData data =
      detail::load_observer_data(u, Eigen::VectorXd(), model.state_space.sample_time());
  if (const auto* p =
          std::get_if<estimation::BidirectionalLoadObserverParameters<double>>(&model.parameters)) {
    return simulate_bidirectional_observer(estimation::BidirectionalLoadObserver<double>(*p), data,
                                           reference);
  }
  return simulate_load_observer(
      estimation::PushLoadObserver<double>(
          files::joint_model_parameters<estimation::PushLoadObserverParameters<double>>(model)),
      data, reference);
}

namespace detail {

// An observer fitted on logs with a third input (the command) must refer its current to it.
inline void require_reference(const char* kind, const std::vector<files::SignalInfo>& inputs,
                              bool has_reference) {
  if (inputs.size() == 3 && !has_reference) {
    endohaptics::detail::fail(std::string("fit_joint_model: ") + kind +
                              ": the current does not follow the third input, " + inputs[2].name +
                              ", or it does not vary (no current-per-command slope can be "
                              "fitted): leave it out");
  }
}

// The causal training fit of an observer on every experiment after `skip` samples (`simulate`:
// its output on one experiment), into out.training_fit and the provenance's mean.
template <typename Simulate>
void score_training(JointModelFit& out, const std::vector<LoadObserverData>& data,
                    Eigen::Index skip, Simulate&& simulate) {
  double sum = 0.0;
  for (const LoadObserverData& d : data) {
    const auto n = d.load.size() - skip;
    out.training_fit.push_back(model::fit_percent(d.load.tail(n), simulate(d).tail(n)));
    sum += out.training_fit.back();
  }
  out.model.provenance.fit_percent = {sum / static_cast<double>(out.training_fit.size())};
}

// fit_joint_model for kind bidirectional_load_observer, on the segments as the observers see them.
// Folds of files as folds of experiments (`file_of[e]`: the file experiment e came from); a fold
// whose files hold no experiment is left out.
inline std::vector<std::vector<std::size_t>> experiment_folds(
    const std::vector<std::vector<std::size_t>>& file_folds,
    const std::vector<std::size_t>& file_of) {
  std::vector<std::vector<std::size_t>> folds;
  for (const auto& held_files : file_folds) {
    std::vector<std::size_t> fold;
    for (std::size_t e = 0; e < file_of.size(); ++e) {
      if (std::find(held_files.begin(), held_files.end(), file_of[e]) != held_files.end()) {
        fold.push_back(e);
      }
    }
    if (!fold.empty()) folds.push_back(std::move(fold));
  }
  return folds;
}

// The joint models' data from logs prepared for scoring, after fit_joint_model's checks: one
// entry per segment longer than the warm-up, `file_of[e]` the file experiment e came from (the
// folds of the constant search hold out whole files).
struct JointData {
  std::vector<StallHoldData> stall_hold{};   // kind stall_hold
  std::vector<LoadObserverData> observer{};  // the observer kinds
  std::vector<std::size_t> file_of{};        // per experiment
  double ts = 0.0;                           // the logs' sample time, s
  double peak = 0.0, sum = 0.0, sum2 = 0.0;  // of the observers' training load
  Eigen::Index count = 0;                    // load samples summed
};

inline JointData joint_data(files::ModelKind kind, const std::vector<PreparedLog>& logs,
                            const std::vector<files::SignalInfo>& inputs,
                            const std::vector<files::SignalInfo>& outputs, double warmup,
                            const char* who) {
  const std::string name(who);
  if (logs.empty()) fail(name + ": no logs");
  if (kind != files::ModelKind::stall_hold && kind != files::ModelKind::push_load_observer &&
      kind != files::ModelKind::bidirectional_load_observer) {
    fail(name + ": kind \"" + std::string(files::to_string(kind)) + "\" is not a joint model");
  }
  const std::size_t most = kind == files::ModelKind::stall_hold ? 2 : 3;
  if (inputs.size() < 2 || inputs.size() > most || outputs.size() != 1) {
    fail(name + ": " + std::string(files::to_string(kind)) + " needs 2 inputs (current, velocity" +
         (most == 3 ? std::string("; a third, the current command, is optional") : std::string()) +
         ") and 1 output, got " + std::to_string(inputs.size()) + " and " +
         std::to_string(outputs.size()));
  }
  // The roles are positional: current, velocity, and for the observer the current command
  // third (named so: a velocity or any other signal there would be taken for the command).
  if (inputs.size() == 3 && (inputs[2].name.find("command") == std::string::npos ||
                             inputs[1].name.find("command") != std::string::npos)) {
    fail(name + ": " + std::string(files::to_string(kind)) +
         " takes (current, velocity, current command) in that order; got (" + inputs[0].name +
         ", " + inputs[1].name + ", " + inputs[2].name + ")");
  }
  for (const PreparedLog& log : logs) {
    for (const DataSet& d : log.segments) {
      if (d.u.cols() != static_cast<Eigen::Index>(inputs.size()) || d.y.cols() != 1) {
        fail(name + ": " + log.source + ": a segment of " + std::to_string(d.u.cols()) +
             " input and " + std::to_string(d.y.cols()) + " output columns, for " +
             std::to_string(inputs.size()) + " inputs and 1 output");
      }
    }
  }
  JointData out;
  out.ts = logs.front().sample_time;
  const auto skip = static_cast<Eigen::Index>(std::ceil(warmup / out.ts));
  for (std::size_t f = 0; f < logs.size(); ++f) {
    for (const DataSet& d : logs[f].segments) {
      if (d.u.rows() <= skip + 1) continue;
      out.file_of.push_back(f);
      if (kind == files::ModelKind::stall_hold) {
        out.stall_hold.push_back({d.u.col(0), d.u.col(1), d.y.col(0)});
        continue;
      }
      LoadObserverData e = load_observer_data(d.u, d.y.col(0), out.ts);
      out.peak = std::max(out.peak, e.load.cwiseAbs().maxCoeff());
      out.sum += e.load.sum();
      out.sum2 += e.load.squaredNorm();
      out.count += e.load.size();
      out.observer.push_back(std::move(e));
    }
  }
  if (out.file_of.empty()) fail(name + ": no segment longer than the warm-up");
  return out;
}

// The search of choose_joint_constants on data from `files` training files: contiguous blocks
// of whole files held out (blocked_folds).
inline JointConstants search_constants(files::ModelKind kind, const JointData& data,
                                       std::size_t files, double warmup) {
  JointConstants out{.kind = kind, .files = files};
  const std::vector<std::vector<std::size_t>> folds =
      experiment_folds(blocked_folds(files), data.file_of);
  if (kind == files::ModelKind::stall_hold) {
    estimation::StallHoldParameters<double> prior;
    prior.sample_time = data.ts;
    // The threshold and the time constants (the dead zone is table 5.2's, physical).
    out.stall_hold = choose_stall_hold_settings(data.stall_hold, folds, prior, warmup);
  } else if (kind == files::ModelKind::bidirectional_load_observer) {
    estimation::BidirectionalLoadObserverParameters<double> prior;
    prior.sample_time = data.ts;
    // Rest is slower than one encoder step per sample (the velocity's quantum: below it the
    // encoder cannot tell motion from rest) when the encoder's step shows in the data; otherwise
    // the threshold is chosen with the others (the noise rule, the cut-offs, q0, the stop scale).
    out.encoder_step = encoder_step(data.observer);
    if (out.encoder_step) prior.velocity_threshold = *out.encoder_step / data.ts;
    out.bidirectional = choose_bidirectional_settings(data.observer, folds, prior, warmup,
                                                      !out.encoder_step.has_value());
  }
  return out;
}

// The constants a fit of `kind` on `files` files uses: `given` (checked against the kind), else
// the search on `data`; `searched` counts the search.
inline JointConstants constants_for(files::ModelKind kind, const JointData& data, std::size_t files,
                                    double warmup, const JointConstants* given,
                                    std::size_t& searched) {
  if (given == nullptr) {
    searched = kind == files::ModelKind::push_load_observer ? 0 : 1;
    return search_constants(kind, data, files, warmup);
  }
  const bool complete =
      given->kind == kind && (kind != files::ModelKind::stall_hold || given->stall_hold) &&
      (kind != files::ModelKind::bidirectional_load_observer || given->bidirectional);
  if (!complete) {
    fail("fit_joint_model: the constants given are for kind \"" +
         std::string(files::to_string(given->kind)) + "\"" +
         (given->kind == kind ? std::string(" but hold none of its constants") : std::string()) +
         ", the fit is of kind \"" + std::string(files::to_string(kind)) + "\"");
  }
  searched = 0;
  return *given;
}

// For the summary of a refit with constants chosen on more files than it uses: which; else "".
inline std::string held_constants(const JointConstants& c, std::size_t files) {
  if (c.files == files) return {};
  return "; chosen on " + std::to_string(c.files) + " training files, held in this refit on " +
         std::to_string(files);
}

inline JointModelFit fit_bidirectional(const JointData& joint, const JointConstants& constants,
                                       std::size_t files, double warmup,
                                       const std::vector<files::SignalInfo>& inputs,
                                       const std::vector<files::SignalInfo>& outputs,
                                       const files::ModelProvenance& provenance) {
  const std::vector<LoadObserverData>& data = joint.observer;
  const double ts = joint.ts;
  estimation::BidirectionalLoadObserverParameters<double> prior;
  prior.sample_time = ts;
  const std::optional<double>& step = constants.encoder_step;
  const BidirectionalSelection& chosen = *constants.bidirectional;
  const auto& c = chosen.settings;
  const BidirectionalObserverFit fit =
      fit_bidirectional_load_observer(data, with_settings(prior, c), warmup, c.rule);
  const std::string unit = outputs.front().unit;
  const std::string how =
      chosen.folds == 0
          ? std::string(
                "the research note's constants (fewer than two training files: no inner "
                "cross-validation)")
          : "chosen by " + std::to_string(chosen.folds) +
                "-fold blocked cross-validation on the training files (" +
                std::to_string(chosen.candidates) + " settings; held-out RMSE " +
                endohaptics::detail::format_number(chosen.held_out_rmse) + " " + unit +
                ", the research note's constants " +
                endohaptics::detail::format_number(chosen.prior_rmse) +
                held_constants(constants, files) + ")";
  const std::string settings =
      "noise rule: correlation time " +
      endohaptics::detail::format_number(c.rule.correlation_time) + " s, friction prior " +
      endohaptics::detail::format_number(c.rule.friction_prior_scale) +
      " x the runs' forward bias, load walk " +
      endohaptics::detail::format_number(100.0 * c.rule.load_walk) +
      " % of the range per root second; front end: current cut-off " +
      endohaptics::detail::format_number(c.current_cutoff) + " Hz, velocity cut-off " +
      endohaptics::detail::format_number(c.velocity_cutoff) + " Hz, q0 " +
      endohaptics::detail::format_number(c.direction_scale) + " rad, velocity threshold " +
      endohaptics::detail::format_number(c.velocity_threshold) + " rad/s" +
      (step ? " (one encoder step, " + endohaptics::detail::format_number(*step) +
                  " rad, per sample)"
            : std::string()) +
      ", stop thresholds x " + endohaptics::detail::format_number(c.stop_scale) + "; " + how;
  const auto& p = fit.parameters;
  const auto& reference = fit.reference;
  require_reference("bidirectional_load_observer", inputs, reference.has_value());
  JointModelFit out{
      .model = files::make_joint_model_file(p, inputs, outputs, provenance, reference),
      .constants = constants};
  const estimation::BidirectionalLoadObserver<double> fitted(p);
  score_training(out, data, static_cast<Eigen::Index>(std::ceil(warmup / ts)),
                 [&](const LoadObserverData& d) {
                   return simulate_bidirectional_observer(fitted, d, reference);
                 });
  const auto map = [&unit](double g, double g1, double o, double o1) {
    return "(" + endohaptics::detail::format_number(g) + " + " +
           endohaptics::detail::format_number(g1) + " s) A/" + unit + ", offset " +
           endohaptics::detail::format_number(o) + " + " + endohaptics::detail::format_number(o1) +
           " s A";
  };
  out.summary =
      "bidirectional_load_observer: forward " +
      endohaptics::detail::format_number(100.0 * fit.forward_fraction) + " %, backward " +
      endohaptics::detail::format_number(100.0 * fit.backward_fraction) +
      " % of the samples; forward map " +
      map(p.forward_gain, p.forward_gain_stroke, p.forward_offset, p.forward_offset_stroke) +
      ", backward map " +
      map(p.backward_gain, p.backward_gain_stroke, p.backward_offset, p.backward_offset_stroke) +
      " (s: the widest stop operator); filter noise sqrt(R) " +
      endohaptics::detail::format_number(std::sqrt(p.forward_variance)) + " / " +
      endohaptics::detail::format_number(std::sqrt(p.backward_variance)) + " " + unit +
      " forward / backward (the inversions' per-sample sd x sqrt(correlation time / Ts): they "
      "err in strokes), "
      "friction prior " +
      endohaptics::detail::format_number(std::sqrt(p.friction_variance)) + " " + unit + " (" +
      endohaptics::detail::format_number(c.rule.friction_prior_scale) +
      " x the runs' forward bias " + endohaptics::detail::format_number(fit.forward_bias_rms) +
      "), initial load " + endohaptics::detail::format_number(p.initial_load) + " " + unit +
      " (sd " + endohaptics::detail::format_number(std::sqrt(p.initial_variance)) +
      "), output hysteresis offset " + endohaptics::detail::format_number(p.output_offset) + " " +
      unit + ", " +
      (reference ? "current referred to the command: " +
                       endohaptics::detail::format_number(reference->command_gain) +
                       " A per command unit, " + "reference offset " +
                       endohaptics::detail::format_number(reference->reference_offset) + " A"
                 : std::string("current as measured (no command)")) +
      "; training RMSE " + endohaptics::detail::format_number(fit.mean_rmse) + " " + unit + "; " +
      settings;
  return out;
}

}  // namespace detail

ENDOHAPTICS_DECL JointConstants
choose_joint_constants(files::ModelKind kind, const std::vector<PreparedLog>& logs,
                       const std::vector<files::SignalInfo>& inputs,
                       const std::vector<files::SignalInfo>& outputs, double warmup) {
  const detail::JointData data =
      detail::joint_data(kind, logs, inputs, outputs, warmup, "choose_joint_constants");
  return detail::search_constants(kind, data, logs.size(), warmup);
}

ENDOHAPTICS_DECL JointModelFit fit_joint_model(files::ModelKind kind,
                                               const std::vector<PreparedLog>& logs,
                                               const std::vector<files::SignalInfo>& inputs,
                                               const std::vector<files::SignalInfo>& outputs,
                                               double warmup, const JointConstants* given) {
  const detail::JointData joint =
      detail::joint_data(kind, logs, inputs, outputs, warmup, "fit_joint_model");
  std::size_t searched = 0;
  // The constants no physics fixes: given (chosen on these files or a superset), or chosen here
  // by cross-validation over the training files.
  const JointConstants constants =
      detail::constants_for(kind, joint, logs.size(), warmup, given, searched);
  const double ts = joint.ts;
  const auto skip = static_cast<Eigen::Index>(std::ceil(warmup / ts));
  files::ModelProvenance provenance;
  provenance.method = std::string(files::to_string(kind));
  for (const PreparedLog& log : logs) provenance.files.push_back(log.source);
  if (kind == files::ModelKind::stall_hold) {
    const std::vector<StallHoldData>& data = joint.stall_hold;
    estimation::StallHoldParameters<double> prior;
    prior.sample_time = ts;
    const StallHoldSelection& chosen = *constants.stall_hold;
    prior.velocity_threshold = chosen.settings.velocity_threshold;
    prior.velocity_time_constant = chosen.settings.velocity_time_constant;
    prior.output_time_constant = chosen.settings.output_time_constant;
    const StallHoldFit fit = fit_stall_hold(data, prior, warmup);
    const auto& p = fit.parameters;
    const std::string side(enumerator_name(p.side));
    provenance.fit_percent = {fit.mean_fit_percent};
    JointModelFit out{.model = files::make_joint_model_file(p, inputs, outputs, provenance),
                      .training_fit = fit.fit_percent,
                      .constants = constants,
                      .constant_searches = searched};
    out.summary =
        "stall_hold: dead zone " + detail::format_number(p.current_deadzone) +
        " A, held at |v| <= " + detail::format_number(p.velocity_threshold) +
        " rad/s, velocity filter " + detail::format_number(p.velocity_time_constant) +
        " s, output lag " + detail::format_number(p.output_time_constant) + " s (" +
        (chosen.folds == 0
             ? std::string("the priors: fewer than two training files, no inner "
                           "cross-validation")
             : "the dead zone table 5.2's; the others by " + std::to_string(chosen.folds) +
                   "-fold blocked cross-validation on the training files, " +
                   std::to_string(chosen.candidates) + " settings, held-out fit " +
                   detail::format_number(chosen.held_out_fit) +
                   " %, the research note's constants " + detail::format_number(chosen.prior_fit) +
                   " %" + detail::held_constants(constants, logs.size())) +
        "); fitted: gain " + detail::format_number(p.gain) + " " + outputs.front().unit +
        "/A, loaded side " + side;
    return out;
  }
  const std::vector<LoadObserverData>& data = joint.observer;
  if (kind == files::ModelKind::bidirectional_load_observer) {
    JointModelFit out = detail::fit_bidirectional(joint, constants, logs.size(), warmup, inputs,
                                                  outputs, provenance);
    out.constant_searches = searched;
    return out;
  }
  const double peak = joint.peak, sum = joint.sum, sum2 = joint.sum2;
  const Eigen::Index count = joint.count;
  const double mean = sum / static_cast<double>(count);
  const double variance = std::max(sum2 / static_cast<double>(count) - mean * mean, 0.0);
  estimation::PushLoadObserverParameters<double> prior;
  prior.sample_time = ts;
  prior.initial_variance = variance > 0 ? variance : 1.0;
  prior.process_variance = std::pow(0.03 * peak, 2) * ts;
  // The push direction is the one in which the motor works against the load: there the
  // current's magnitude grows with the load (|d_p + c_p load| increases with |load|, at the
  // training-mean load); the other direction is back-driven, its current shrinks with the load.
  // Among the signs that satisfy this, the better causal training RMSE; only if none does, the
  // better RMSE alone (on the UMN logs the back-driven fit has the lower training RMSE but does
  // not carry over to another session: 20 vs 6.8 mN m on five runs).
  const auto works_against = [](const LoadObserverFit& f) {
    const auto& q = f.parameters;
    const double load_term = q.current_per_load * q.initial_load;
    return load_term * (q.current_offset + load_term) > 0.0;
  };
  std::optional<LoadObserverFit> best;
  std::string failures;
  for (const double sign : {1.0, -1.0}) {
    prior.push_sign = sign;
#if defined(__cpp_exceptions)
    try {
#endif
      LoadObserverFit fit = fit_push_load_observer(data, prior, warmup);
      const bool better =
          !best || (works_against(fit) && !works_against(*best)) ||
          (works_against(fit) == works_against(*best) && fit.mean_rmse < best->mean_rmse);
      if (better) best = std::move(fit);
#if defined(__cpp_exceptions)
    } catch (const Error& e) {
      failures += std::string(failures.empty() ? "" : "; ") + "push sign " +
                  detail::format_number(sign) + ": " + e.what();
    }
#endif
  }
  if (!best) detail::fail("fit_joint_model: push_load_observer: " + failures);
  const auto& p = best->parameters;
  const auto& reference = best->reference;
  detail::require_reference("push_load_observer", inputs, reference.has_value());
  JointModelFit out{
      .model = files::make_joint_model_file(p, inputs, outputs, provenance, reference),
      .constants = constants};
  const estimation::PushLoadObserver<double> fitted(p);
  detail::score_training(out, data, skip, [&](const LoadObserverData& d) {
    return simulate_load_observer(fitted, d, reference);
  });
  const std::string unit = outputs.front().unit;
  out.summary =
      "push_load_observer: push sign " + detail::format_number(p.push_sign) +
      " (of +1, -1: the motor works against the load, |current| grows with it" +
      std::string(works_against(*best) ? "" : ": NOT met by either sign, the better RMSE") +
      "), push regime " + detail::format_number(100.0 * best->push_fraction) +
      " % of the samples; fitted: current per load " + detail::format_number(p.current_per_load) +
      " A/" + unit + ", offset " + detail::format_number(p.current_offset) + " A, per velocity " +
      detail::format_number(p.current_per_velocity) + " A s/rad, R " +
      detail::format_number(p.measurement_variance) + " A^2, load-side friction " +
      detail::format_number(p.output_offset) + " " + unit + " + " +
      detail::format_number(p.output_slope) + " x load, initial load " +
      detail::format_number(p.initial_load) + " " + unit + ", " +
      (p.back_current_per_load != 0.0
           ? "before the first push the back-driven map " +
                 detail::format_number(p.back_current_per_load) + " A/" + unit + ", offset " +
                 detail::format_number(p.back_current_offset) + " A (its RMS error " +
                 detail::format_number(std::sqrt(p.back_variance)) + " " + unit + ")"
           : std::string("no back-driven map (the prior until the first push)")) +
      ", stiffness " + detail::format_number(p.load_per_angle) + " " + unit +
      "/rad of travel after the first push, " +
      (reference
           ? "current referred to the command: " + detail::format_number(reference->command_gain) +
                 " A per command unit, " + "reference offset " +
                 detail::format_number(reference->reference_offset) + " A"
           : std::string("current as measured (no command)")) +
      "; priors: Q " + detail::format_number(p.process_variance) + " per step, P0 " +
      detail::format_number(p.initial_variance) + ", filters " +
      detail::format_number(p.current_cutoff) + "/" + detail::format_number(p.velocity_cutoff) +
      " Hz, q0 " + detail::format_number(p.direction_scale) + " rad";
  return out;
}

ENDOHAPTICS_DECL std::vector<std::vector<std::size_t>> inner_folds(std::size_t files) {
  std::vector<std::vector<std::size_t>> folds;
  if (files < 2) return folds;
  const std::size_t k = std::min<std::size_t>(files, 5);
  folds.resize(k);
  for (std::size_t i = 0; i < files; ++i) folds[i % k].push_back(i);
  return folds;
}

ENDOHAPTICS_DECL std::vector<std::vector<std::size_t>> blocked_folds(std::size_t files) {
  std::vector<std::vector<std::size_t>> folds;
  if (files < 2) return folds;
  const std::size_t k = std::min<std::size_t>(files, 5);
  std::size_t next = 0;
  for (std::size_t f = 0; f < k; ++f) {
    const std::size_t size = files / k + (f < files % k ? 1 : 0);
    folds.emplace_back();
    for (std::size_t i = 0; i < size; ++i) folds.back().push_back(next++);
  }
  return folds;
}

}  // namespace endohaptics::workflow
