//! @file
//! fit_stall_hold: identifies estimation::StallHold from logs. The dead zone is physical (table
//! 5.2's static friction of the clamp, measured apart from any log); the velocity threshold and
//! the two time constants are chosen by cross-validation on the training files
//! (choose_stall_hold_settings; their defaults in StallHoldParameters were set after looking at
//! held-out fits, so are not used as they stand when there are folds); the gain and the loaded
//! side are fitted by linear least squares on the causal run of the unit-gain model (state from
//! zero, a warm-up excluded, no output used for any state), so the score reported is a causal one.
//! Configuration time: allocates, throws endohaptics::Error.
#pragma once

#include <Eigen/Core>
#include <algorithm>
#include <array>
#include <cmath>
#include <cstddef>
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

//! The constants of StallHold that no physics fixes, chosen by choose_stall_hold_settings.
struct StallHoldSettings {
  double velocity_threshold = 0.05;      //!< rad/s: at or below, stalled
  double velocity_time_constant = 0.03;  //!< s, the velocity's low-pass
  double output_time_constant = 0.3;     //!< s, the output's lag
};

//! What choose_stall_hold_settings chose and why.
struct StallHoldSelection {
  StallHoldSettings settings{};  //!< the chosen constants
  //! Their mean held-out causal fit over the inner folds, %.
  double held_out_fit = -std::numeric_limits<double>::infinity();
  //! The same for the prior's constants (the research note's A1 values).
  double prior_fit = -std::numeric_limits<double>::infinity();
  std::size_t candidates = 0;  //!< settings scored
  std::size_t folds = 0;       //!< inner folds (0: too few files, the prior kept)
};

//! Chooses StallHoldSettings by cross-validation over `folds` (each a list of indices into
//! `data` held out together; the others train, fit_stall_hold): the mean causal fit % of the
//! held-out experiments after the warm-up, each held out once. A grid (velocity threshold 0.0125,
//! 0.025, 0.05, 0.1, 0.2 rad/s x velocity time constant 0.01, 0.03, 0.1 s x output time constant
//! 0.1, 0.15, 0.2, 0.3, 0.4, 0.6, 0.8 s), then a constant whose best value lies on the grid's edge
//! is walked beyond it by a factor of 2 while the score improves (at most 3 steps). The dead zone
//! and the sample time are the prior's. A candidate that fails on a fold loses. With fewer than two
//! folds, or when every candidate fails, the prior's constants (folds 0). Deterministic.
[[nodiscard]] ENDOHAPTICS_DECL StallHoldSelection choose_stall_hold_settings(
    std::span<const StallHoldData> data, const std::vector<std::vector<std::size_t>>& folds,
    const estimation::StallHoldParameters<double>& prior, double warmup);

}  // namespace endohaptics::workflow

#if !defined(ENDOHAPTICS_SEPARATE_COMPILATION)
#include "endohaptics/workflow/impl/stall_hold_fit.ipp"
#endif
