//! @file
//! A model file replayed on prepared logs and scored as a force estimator (worksheet 4.2,
//! issue 15): input maps, linear block and output maps simulated segment by segment from an
//! initial state set from the inputs alone (steady state of the first input sample; or zero, or
//! the file's x0), the first `warmup` s of each segment left out of the score, then NRMSE fit (%),
//! correlation, RMSE (output units) and the delay of the estimate (s, cross-correlation peak) over
//! the whole file (identification/fit_metrics.hpp). `oracle` (x0 by least squares on the measured
//! output, MATLAB compare's default) is there only as a labelled comparison.
//! Configuration time: throws endohaptics::Error.
#pragma once

#include <Eigen/Core>
#include <Eigen/LU>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <limits>
#include <string>
#include <string_view>
#include <vector>

#include "endohaptics/files/model_file.hpp"
#include "endohaptics/identification/fit_metrics.hpp"
#include "endohaptics/identification/hammerstein_wiener_fit.hpp"
#include "endohaptics/identification/subspace.hpp"
#include "endohaptics/model/state_space.hpp"
#include "endohaptics/model/static_map.hpp"
#include "endohaptics/workflow/error_context.hpp"
#include "endohaptics/workflow/prepared_log.hpp"

namespace endohaptics::workflow {

using namespace endohaptics::identification;  // the workflow composes the identification area

//! How replay/compare set the initial state of every segment.
enum class InitialStateMode : std::uint8_t {
  steady,  //!< steady state for the first (mapped) input sample: inputs only (the default)
  zero,    //!< x0 = 0
  stored,  //!< the model file's x0 (a model parameter, e.g. the static baseline's constant)
  oracle,  //!< least squares on the measured output (MATLAB compare's default): NOT causal
};

//! Lower-case name ("steady", "zero", "stored", "oracle").
[[nodiscard]] constexpr std::string_view to_string(InitialStateMode mode) noexcept {
  switch (mode) {
    case InitialStateMode::steady:
      return "steady";
    case InitialStateMode::zero:
      return "zero";
    case InitialStateMode::stored:
      return "stored";
    case InitialStateMode::oracle:
      return "oracle";
  }
  return "unknown";
}

//! True when the mode uses nothing but the inputs (and the model) to set the state.
[[nodiscard]] constexpr bool is_causal(InitialStateMode mode) noexcept {
  return mode != InitialStateMode::oracle;
}

//! How a model is scored on a log.
struct ScoringOptions {
  InitialStateMode initial_state = InitialStateMode::steady;  //!< how x0 is set per segment
  //! s at the start of each segment simulated but left out of the score (the state settles
  //! from its input-only start); at most max_warmup. 0 with `oracle` (MATLAB compare).
  double warmup = 0.5;
  double max_lag = 1.0;  //!< s, largest |delay| searched by the cross-correlation
};

//! Largest warm-up accepted, s (issue 15: a stated warm-up of at most 1 s).
inline constexpr double max_warmup = 1.0;

//! A model simulated on one prepared log, segment by segment, and its scores over the whole file.
struct FileComparison {
  std::string source;                  //!< file
  std::vector<Eigen::MatrixXd> y;      //!< measured output per segment (as prepared)
  std::vector<Eigen::MatrixXd> y_hat;  //!< simulated output per segment
  std::vector<double> start_time;      //!< s, per segment
  double sample_time = 0.0;            //!< s
  Eigen::Index warmup_samples = 0;     //!< per segment, left out of the scores
  Eigen::Index scored_samples = 0;     //!< over all segments
  Eigen::VectorXd fit;                 //!< NRMSE fit per output over the scored samples, %
  Eigen::VectorXd correlation;         //!< per output
  Eigen::VectorXd rmse;                //!< per output, output units
  Eigen::VectorXd delay;               //!< per output, s: lag of the estimate behind the truth

  //! Mean of `fit` over the outputs, %.
  [[nodiscard]] double mean_fit() const { return fit.mean(); }
  //! Mean of `rmse` over the outputs, output units.
  [[nodiscard]] double mean_rmse() const { return rmse.mean(); }
};

//! The state x with x = A x + B u0 (the steady state for a constant input u0, already through
//! the input maps). A model whose A has no such state (an eigenvalue at 1): when it is the
//! static baseline's constant (A = I, B = 0) its stored x0; otherwise throws Error.
[[nodiscard]] inline Eigen::VectorXd steady_initial_state(const model::DynamicStateSpace<>& linear,
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

//! Simulates the model file (input maps, linear block, output maps) on every segment of `log`
//! from x0 as `options.initial_state` says, leaves the first `options.warmup` s of each segment
//! (all but its last sample when shorter) out, and scores the rest of the file together.
//! Throws Error when the log's input or output count differs from the model's, or the warm-up is
//! outside [0, max_warmup].
[[nodiscard]] inline FileComparison compare_log(const files::ModelFile& model,
                                                const PreparedLog& log,
                                                const ScoringOptions& options = {}) {
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
    const Eigen::MatrixXd u = apply_maps(in_maps, d.u);
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
    const Eigen::MatrixXd y_hat = apply_maps(out_maps, simulate(linear, u, x0));
    const Eigen::Index skip = std::min(c.warmup_samples, d.y.rows() - 1);
    const Eigen::Index keep = d.y.rows() - skip;
    y_all.middleRows(row, keep) = d.y.bottomRows(keep);
    y_hat_all.middleRows(row, keep) = y_hat.bottomRows(keep);
    row += keep;
    c.y.push_back(d.y);
    c.y_hat.push_back(y_hat);
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

//! Throws Error naming the file and the output when a score of `c` is not finite, so that a
//! program never reports such a run as a success: a simulated output that diverges (an unstable
//! model: fit -Inf), a constant measured output the model does not match (fit -Inf), or a
//! constant measured or simulated output (correlation undefined). `outputs` names the outputs
//! (fewer names: numbered).
inline void require_finite_scores(const FileComparison& c,
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
