//! @file
//! fit_bidirectional_load_observer: identifies estimation::BidirectionalLoadObserver from logs by
//! linear least squares (docs/research_force_models.md, K7; the rules in
//! docs/identification_results.md, "Their fits"): each experiment one load level (its mean truth),
//! the two maps and the output's hysteresis around it, the filter's noise from the inversions.
//! Configuration time: allocates, throws endohaptics::Error.
#pragma once

#include <Eigen/Dense>
#include <algorithm>
#include <cmath>
#include <limits>
#include <span>
#include <string>
#include <utility>
#include <vector>
#include "endohaptics/core/separate_compilation.hpp"

#include "endohaptics/core/error.hpp"
#include "endohaptics/estimation/bidirectional_load_observer.hpp"
#include "endohaptics/workflow/push_load_observer_fit.hpp"

namespace endohaptics::workflow {

//! What fit_bidirectional_load_observer found.
struct BidirectionalObserverFit {
  estimation::BidirectionalLoadObserverParameters<double> parameters;  //!< priors + fitted values
  CurrentReference reference{};    //!< G and b_ref when every experiment has the command, else none
  std::vector<double> rmse;        //!< causal RMSE per experiment after the warm-up, load units
  double mean_rmse = 0.0;          //!< their mean
  double forward_fraction = 0.0;   //!< share of the samples moving forward
  double backward_fraction = 0.0;  //!< share of the samples moving back
  double forward_bias_rms = 0.0;   //!< RMS over the experiments of the forward inversion's bias
};

//! Seconds over which the inversion errors are taken as correlated (R = per-sample variance x
//! this / Ts): the research note's 0.2 s (K7).
inline constexpr double bidirectional_inversion_correlation_time = 0.2;
//! The friction prior's standard deviation in units of the training runs' forward bias RMS (K7).
inline constexpr double bidirectional_friction_prior_scale = 2.5;

//! The causal output of `model` (from its reset state) on one experiment; with a `reference`, the
//! current referred to the command first (the experiment must then carry it).
[[nodiscard]] ENDOHAPTICS_DECL Eigen::VectorXd simulate_bidirectional_observer(
    const estimation::BidirectionalLoadObserver<double>& model, const LoadObserverData& d,
    const CurrentReference& reference = std::nullopt);

//! Fits the current's offset reference (when every experiment carries the command: the current is
//! referred to it first, estimation/current_offset_reference.hpp), then with each experiment
//! weighing the same and its first `warmup` s left out: (a) on the forward samples, the filtered
//! current on [L_e, L_e s_N, 1, s_N] (L_e the experiment's mean load) gives the forward map, on
//! the backward samples the backward map; (b) (load - L_e) on [1, s_1..s_N, L_e s_1..L_e s_N]
//! gives e0, a_j, b_j; (c) R = the mean square of each map's inversion z - L_e times
//! bidirectional_inversion_correlation_time / Ts (the inversion errors run in strokes, not
//! white), the friction prior (bidirectional_friction_prior_scale x the RMS of the experiments'
//! forward bias)^2, at least the forward inversion's mean square, Q_L = (0.01 max |load|)^2 Ts,
//! the initial load and its variance from the training loads. The filters, thresholds and stop
//! thresholds come from `prior`. Throws Error on empty or mismatched
//! data, a warm-up that is not finite and >= 0, fewer than 10 samples in either direction,
//! experiments all at one load level, a singular fit, a map whose gain would fall below a tenth
//! along the stroke, maps of opposite signs, or variances beyond the model's bound.
[[nodiscard]] ENDOHAPTICS_DECL BidirectionalObserverFit fit_bidirectional_load_observer(
    std::span<const LoadObserverData> data,
    const estimation::BidirectionalLoadObserverParameters<double>& prior, double warmup = 1.0);

}  // namespace endohaptics::workflow

#if !defined(ENDOHAPTICS_SEPARATE_COMPILATION)
#include "endohaptics/workflow/impl/bidirectional_observer_fit.ipp"
#endif
