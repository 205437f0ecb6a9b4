//! @file
//! fit_bidirectional_load_observer: identifies estimation::BidirectionalLoadObserver from logs by
//! linear least squares (docs/research_force_models.md, K7). Each experiment is taken to hold one
//! load level L_e, the mean of its truth after the warm-up (the UMN protocol: a constant reaction
//! torque per run), around which the load moves along the stroke. (a) On the forward samples, the
//! filtered current on [L_e, L_e s_N, 1, s_N] gives the forward map; on the backward samples, the
//! backward map. (b) (load - L_e) on [1, s_1..s_N, L_e s_1..L_e s_N] gives the output's hysteresis
//! e0, a_j, b_j. (c) The maps' inversions on the training samples give the filter's noise: R =
//! the per-sample variance of the inversion times the correlation time over the sample time (the
//! inversion errors run in strokes, not white), the friction prior (2.5 x the RMS of the runs'
//! forward bias, at least one sample's variance: a new instrument's friction spreads wider than
//! the training runs'), Q_L = (0.01 max |load|)^2 Ts (1 % of the range per root second). When every
//! experiment carries the command, the current is first referred to it
//! (estimation/current_offset_reference.hpp). Every experiment weighs the same. Configuration
//! time: allocates, throws endohaptics::Error.
#pragma once

#include <Eigen/Dense>
#include <algorithm>
#include <cmath>
#include <limits>
#include <span>
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

//! Fits the current's offset reference (when the data carry the command), both maps, the noise,
//! the friction prior, the initial load and the output's hysteresis (see the file comment); the
//! filters, thresholds and stop thresholds come from `prior`. Throws Error on empty or mismatched
//! data, fewer than 10 samples in either direction, experiments all at one load level, a singular
//! fit or a map whose gain changes sign along the stroke.
[[nodiscard]] ENDOHAPTICS_DECL BidirectionalObserverFit fit_bidirectional_load_observer(
    std::span<const LoadObserverData> data,
    const estimation::BidirectionalLoadObserverParameters<double>& prior, double warmup = 1.0);

}  // namespace endohaptics::workflow

#if !defined(ENDOHAPTICS_SEPARATE_COMPILATION)
#include "endohaptics/workflow/impl/bidirectional_observer_fit.ipp"
#endif
