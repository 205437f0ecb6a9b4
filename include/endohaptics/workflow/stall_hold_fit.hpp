//! @file
//! fit_stall_hold: identifies estimation::StallHold from logs. The dead zone, the velocity
//! threshold and both time constants are priors (physical: table 5.2's static friction, a little
//! above the velocity noise, the load cell's lag); the gain and the loaded side are fitted by
//! linear least squares on the causal run of the unit-gain model (state from zero, a warm-up
//! excluded, no output used for any state), so the score reported is a causal one.
//! Configuration time: allocates, throws endohaptics::Error.
#pragma once

#include <Eigen/Core>
#include <array>
#include <cmath>
#include <limits>
#include <span>
#include <string>
#include <vector>

#include "endohaptics/core/error.hpp"
#include "endohaptics/estimation/stall_hold.hpp"

namespace endohaptics::workflow {

//! One experiment on the model's uniform grid (sample_time apart): current (A), velocity (rad/s)
//! and the measured force (what the model should reproduce).
struct StallHoldData {
  Eigen::VectorXd current;   //!< A
  Eigen::VectorXd velocity;  //!< rad/s
  Eigen::VectorXd force;     //!< the truth, in the gain's unit
};

//! What fit_stall_hold found.
struct StallHoldFit {
  estimation::StallHoldParameters<double> parameters;  //!< the priors, the fitted gain and side
  std::vector<double> fit_percent;  //!< causal NRMSE fit % per experiment, after the warm-up
  double mean_fit_percent = 0.0;    //!< their mean
};

//! The causal output of `model` (state from zero) on one experiment, one value per sample.
[[nodiscard]] inline Eigen::VectorXd simulate_stall_hold(const estimation::StallHold<double>& model,
                                                         const StallHoldData& d) {
  estimation::StallHold<double> m = model;
  m.reset();
  Eigen::VectorXd y(d.current.size());
  for (Eigen::Index k = 0; k < d.current.size(); ++k) {
    const estimation::JointSignals<double> s{0.0, d.velocity[k], d.current[k], 0.0};
    if (m.advance(s) != model::StepStatus::ok) {
      ENDOHAPTICS_THROW(
          Error("simulate_stall_hold: non-finite signal at sample " + std::to_string(k)));
    }
    y[k] = m.force(s);
  }
  return y;
}

//! Fits the gain (least squares over every experiment after `warmup` s, each experiment weighted
//! by 1 / its length) for each side (both, positive, negative) and keeps the side with the best
//! mean causal fit. `prior`: dead zone, threshold, time constants and sample time (gain and side
//! are overwritten). Throws Error on empty or mismatched data or a model that never leaves zero.
[[nodiscard]] inline StallHoldFit fit_stall_hold(
    std::span<const StallHoldData> data, const estimation::StallHoldParameters<double>& prior,
    double warmup = 1.0) {
  if (data.empty()) ENDOHAPTICS_THROW(Error("fit_stall_hold: no data"));
  if (!(std::isfinite(warmup) && warmup >= 0)) {
    ENDOHAPTICS_THROW(Error("fit_stall_hold: warmup must be finite and >= 0 s, got " +
                            endohaptics::detail::format_number(warmup)));
  }
  prior.validate();
  const auto skip = static_cast<Eigen::Index>(std::ceil(warmup / prior.sample_time));
  for (std::size_t e = 0; e < data.size(); ++e) {
    const auto& d = data[e];
    if (d.velocity.size() != d.current.size() || d.force.size() != d.current.size()) {
      ENDOHAPTICS_THROW(Error("fit_stall_hold: experiment " + std::to_string(e) +
                              ": current, velocity and force differ in length"));
    }
    if (d.current.size() <= skip + 1) {
      ENDOHAPTICS_THROW(Error("fit_stall_hold: experiment " + std::to_string(e) + " has " +
                              std::to_string(d.current.size()) +
                              " samples, not more than the warm-up"));
    }
  }
  StallHoldFit best;
  best.mean_fit_percent = -std::numeric_limits<double>::infinity();
  for (const auto side : {estimation::StallHoldSide::both, estimation::StallHoldSide::positive,
                          estimation::StallHoldSide::negative}) {
    auto p = prior;
    p.side = side;
    p.gain = 1.0;
    const estimation::StallHold<double> unit(p);
    std::vector<Eigen::VectorXd> shapes;
    double num = 0.0, den = 0.0;
    for (const auto& d : data) {
      shapes.push_back(simulate_stall_hold(unit, d));
      const auto n = d.current.size() - skip;
      const auto z = shapes.back().tail(n);
      num += z.dot(d.force.tail(n)) / static_cast<double>(n);
      den += z.squaredNorm() / static_cast<double>(n);
    }
    if (!(den > 0)) continue;  // this side never leaves zero on these data
    p.gain = num / den;
    StallHoldFit candidate;
    candidate.parameters = p;
    double sum = 0.0;
    for (std::size_t e = 0; e < data.size(); ++e) {
      const auto n = data[e].current.size() - skip;
      const Eigen::VectorXd y = data[e].force.tail(n);
      const Eigen::VectorXd y_hat = p.gain * shapes[e].tail(n);
      const double spread = (y.array() - y.mean()).matrix().norm();
      const double fit = spread > 0 ? 100.0 * (1.0 - (y - y_hat).norm() / spread)
                                    : -std::numeric_limits<double>::infinity();
      candidate.fit_percent.push_back(fit);
      sum += fit;
    }
    candidate.mean_fit_percent = sum / static_cast<double>(data.size());
    if (candidate.mean_fit_percent > best.mean_fit_percent) best = std::move(candidate);
  }
  if (best.fit_percent.empty()) {
    ENDOHAPTICS_THROW(Error("fit_stall_hold: the current never exceeds the dead zone of " +
                            endohaptics::detail::format_number(prior.current_deadzone) +
                            " A while the joint moves: nothing to fit"));
  }
  return best;
}

}  // namespace endohaptics::workflow
