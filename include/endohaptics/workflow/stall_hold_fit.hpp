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
#include "endohaptics/core/separate_compilation.hpp"

#include "endohaptics/core/error.hpp"
#include "endohaptics/estimation/simulate.hpp"
#include "endohaptics/estimation/stall_hold.hpp"
#include "endohaptics/model/fit_metric.hpp"

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
[[nodiscard]] ENDOHAPTICS_DECL Eigen::VectorXd simulate_stall_hold(
    const estimation::StallHold<double>& model, const StallHoldData& d);

//! Fits the gain (least squares over every experiment after `warmup` s, each experiment weighted
//! by 1 / its length) for each side (both, positive, negative) and keeps the side with the best
//! mean causal fit. `prior`: dead zone, threshold, time constants and sample time (gain and side
//! are overwritten). Throws Error on empty or mismatched data or a model that never leaves zero.
[[nodiscard]] ENDOHAPTICS_DECL StallHoldFit
fit_stall_hold(std::span<const StallHoldData> data,
               const estimation::StallHoldParameters<double>& prior, double warmup = 1.0);

}  // namespace endohaptics::workflow

#if !defined(ENDOHAPTICS_SEPARATE_COMPILATION)
#include "endohaptics/workflow/impl/stall_hold_fit.ipp"
#endif
