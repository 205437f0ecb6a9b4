//! @file
//! Function bodies of workflow/model_comparison.hpp: included at its end (header-only, the
//! default), or compiled once with ENDOHAPTICS_SEPARATE_COMPILATION
//! (core/separate_compilation.hpp).
#pragma once

#include <utility>

#include "endohaptics/model/stop_operators.hpp"
#include "endohaptics/workflow/model_comparison.hpp"

namespace endohaptics::workflow {

ENDOHAPTICS_DECL Eigen::VectorXd steady_initial_state(const model::DynamicStateSpace<>& linear,
                                                      const Eigen::VectorXd& u0) {
  const Eigen::MatrixXd& A = linear.A();
  const Eigen::MatrixXd& B = linear.B();
  const Eigen::Index n = A.rows();
  if (n == 0) return Eigen::VectorXd::Zero(0);
  if (A.isIdentity(0.0) && B.isZero(0.0)) return linear.state();
  const Eigen::MatrixXd I_minus_A = Eigen::MatrixXd::Identity(n, n) - A;
  const Eigen::FullPivLU<Eigen::MatrixXd> lu(I_minus_A);
  Eigen::VectorXd x = Eigen::VectorXd::Zero(n);
  if (lu.isInvertible()) x = lu.solve(B * u0);
  if (!lu.isInvertible() || !x.allFinite()) {
    detail::fail(
        "steady_initial_state: the model has an eigenvalue at 1 (an integrator): no steady "
        "state for the first input; use --x0 zero");
  }
  return x;
}

ENDOHAPTICS_DECL FileComparison compare_log(const files::ModelFile& model, const PreparedLog& log,
                                            const ScoringOptions& options) {
  namespace wf = detail;
  const auto& linear = model.state_space;  // the linear block, x0 = its state
  const auto nu = static_cast<Eigen::Index>(model.inputs.size());
  const auto ny = static_cast<Eigen::Index>(model.outputs.size());
  if (log.segments.empty()) wf::fail(log.source + ": no segments to compare");
  if (log.segments.front().u.cols() != nu || log.segments.front().y.cols() != ny) {
    wf::fail(log.source + ": the log gives " + std::to_string(log.segments.front().u.cols()) +
             " inputs and " + std::to_string(log.segments.front().y.cols()) +
             " outputs, the model has " + std::to_string(nu) + " and " + std::to_string(ny));
  }
  if (!(options.warmup >= 0.0 && options.warmup <= max_warmup)) {
    wf::fail("warm-up must be in [0, " + wf::format_number(max_warmup) + "] s, got " +
             wf::format_number(options.warmup));
  }
  if (!(options.max_lag >= 0.0 && std::isfinite(options.max_lag))) {
    wf::fail("max_lag must be finite and >= 0 s, got " + wf::format_number(options.max_lag));
  }
  if (model.is_joint_model() && options.initial_state == InitialStateMode::oracle) {
    wf::fail("--x0 oracle: a " + std::string(files::to_string(model.kind())) +
             " model has no linear state to fit to the output (it starts from its reset state, "
             "filters at the first sample); score it causally (--x0 steady, the default)");
  }
  if (options.clamp_preset && options.initial_state == InitialStateMode::oracle) {
    wf::fail("--x0 oracle: preset:" + std::string(estimation::to_string(*options.clamp_preset)) +
             " runs as the bridge runs it, from its reset state: no linear state to fit to the "
             "output; score it causally (--x0 steady, the default)");
  }
  if (model.is_joint_model() && std::abs(log.sample_time - model.state_space.sample_time()) >
                                    1e-9 * model.state_space.sample_time()) {
    wf::fail(log.source + ": prepared at " + wf::format_number(log.sample_time) + " s, the " +
             std::string(files::to_string(model.kind())) + " model runs at " +
             wf::format_number(model.state_space.sample_time()) + " s");
  }
  std::vector<StaticMap> in_maps = model.input_nonlinearity;
  std::vector<StaticMap> out_maps = model.output_nonlinearity;
  if (in_maps.empty()) in_maps.assign(static_cast<std::size_t>(nu), StaticMap{});
  if (out_maps.empty()) out_maps.assign(static_cast<std::size_t>(ny), StaticMap{});
  FileComparison c;
  c.source = log.source;
  c.sample_time = log.sample_time;
  c.start_time = log.start_time;
  c.warmup_samples =
      static_cast<Eigen::Index>(std::llround(options.warmup / std::max(log.sample_time, 1e-300)));
  Eigen::Index total = 0;
  for (const DataSet& d : log.segments) {
    total += d.y.rows() - std::min(c.warmup_samples, d.y.rows() - 1);
  }
  Eigen::MatrixXd y_all(total, ny);
  Eigen::MatrixXd y_hat_all(total, ny);
  Eigen::Index row = 0;
  for (const DataSet& d : log.segments) {
    Eigen::MatrixXd y_hat;
    if (options.clamp_preset) {  // the bridge's estimator with the preset, from reset
      y_hat = wf::with_context(log.source, [&] {
        return Eigen::MatrixXd(simulate_clamp_preset(*options.clamp_preset, d.u, log.sample_time));
      });
    } else if (model.is_joint_model()) {  // a joint model: causal from its start state, no x0
      y_hat = wf::with_context(log.source,
                               [&] { return Eigen::MatrixXd(simulate_joint_model(model, d.u)); });
    } else {
      const Eigen::MatrixXd u = apply_maps(
          in_maps, identification::played_input(d.u, model.current_play,
                                                endohaptics::model::friction_play_slide(
                                                    model.current_play, model.current_play_slide),
                                                model.current_play_viscous));
      Eigen::VectorXd x0 = Eigen::VectorXd::Zero(linear.state_size());
      switch (options.initial_state) {
        case InitialStateMode::oracle:
          x0 = wf::with_context(log.source, [&] { return estimate_initial_state(linear, u, d.y); });
          break;
        case InitialStateMode::stored:
          x0 = linear.state();
          break;
        case InitialStateMode::steady:
          x0 = wf::with_context(log.source,
                                [&] { return steady_initial_state(linear, u.row(0).transpose()); });
          break;
        case InitialStateMode::zero:
          break;
      }
      y_hat = apply_maps(out_maps, simulate(linear, u, x0));
      if (model.free_motion_threshold > 0.0) {  // as the bridge runs the model
        const endohaptics::model::FreeMotionThreshold<double> threshold(
            model.free_motion_threshold);
        y_hat = y_hat.unaryExpr([&](double v) { return threshold.apply(v); });
      }
    }
    const Eigen::Index skip = std::min(c.warmup_samples, d.y.rows() - 1);
    const Eigen::Index keep = d.y.rows() - skip;
    y_all.middleRows(row, keep) = d.y.bottomRows(keep);
    y_hat_all.middleRows(row, keep) = y_hat.bottomRows(keep);
    row += keep;
    c.y.push_back(d.y);
    c.y_hat.push_back(std::move(y_hat));
  }
  c.scored_samples = total;
  // A diverging model gives Inf/NaN: report fit -Inf rather than failing on the metric.
  if (!y_hat_all.allFinite()) {
    c.fit = Eigen::VectorXd::Constant(ny, -std::numeric_limits<double>::infinity());
    c.correlation = Eigen::VectorXd::Constant(ny, std::numeric_limits<double>::quiet_NaN());
    c.rmse = Eigen::VectorXd::Constant(ny, std::numeric_limits<double>::infinity());
    c.delay = Eigen::VectorXd::Constant(ny, std::numeric_limits<double>::quiet_NaN());
    return c;
  }
  c.fit = nrmse_fit(y_all, y_hat_all);
  c.correlation = correlation(y_all, y_hat_all);
  c.rmse = rmse(y_all, y_hat_all);
  // The delay within segments only would be cleaner; across the joins of the concatenation the
  // few mismatched products do not move the peak of a long file.
  const auto max_lag =
      static_cast<Eigen::Index>(std::llround(options.max_lag / std::max(log.sample_time, 1e-300)));
  c.delay = cross_correlation_lag(y_all, y_hat_all, max_lag) * log.sample_time;
  return c;
}

ENDOHAPTICS_DECL void require_finite_scores(const FileComparison& c,
                                            const std::vector<std::string>& outputs) {
  const auto name = [&](Eigen::Index i) {
    const auto k = static_cast<std::size_t>(i);
    return k < outputs.size() ? "'" + outputs[k] + "'" : "output " + std::to_string(i);
  };
  bool diverged = false;
  for (const Eigen::MatrixXd& y_hat : c.y_hat) diverged = diverged || !y_hat.allFinite();
  if (diverged) {
    detail::fail(c.source +
                 ": the simulated output is not finite: the model diverges on this log " +
                 "(unstable, or unstable for these inputs); no fit can be given");
  }
  for (Eigen::Index i = 0; i < c.fit.size(); ++i) {
    if (!std::isfinite(c.fit[i])) {
      detail::fail(c.source + ": fit of " + name(i) + " is " + detail::format_number(c.fit[i]) +
                   ": the measured output is constant and the model does not reproduce it");
    }
    if (i < c.correlation.size() && !std::isfinite(c.correlation[i])) {
      detail::fail(c.source + ": correlation of " + name(i) +
                   " is undefined: the measured or the simulated output is constant");
    }
    if (i < c.rmse.size() && !std::isfinite(c.rmse[i])) {
      detail::fail(c.source + ": RMSE of " + name(i) + " is not finite");
    }
  }
}

}  // namespace endohaptics::workflow
