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
#include <cstddef>
#include <initializer_list>
#include <iterator>
#include <limits>
#include <optional>
#include <span>
#include <string>
#include <utility>
#include <vector>
#include "endohaptics/core/separate_compilation.hpp"

#include "endohaptics/core/error.hpp"
#include "endohaptics/estimation/bidirectional_load_observer.hpp"
#include "endohaptics/workflow/push_load_observer_fit.hpp"

namespace endohaptics::workflow {

//! The fit's noise rule: three constants that no physics fixes. The defaults are the research
//! note's (K7), set after a sweep that scored both UMN sessions, so not blind: identify does not
//! use them as they stand but chooses each by choose_bidirectional_settings's inner
//! cross-validation on the training files (fit_joint_model).
struct BidirectionalNoiseRule {
  //! s: R = an inversion's per-sample variance x this / Ts (its errors come in strokes, not white)
  double correlation_time = 0.2;
  //! The friction prior's standard deviation in units of the training runs' forward bias RMS.
  double friction_prior_scale = 2.5;
  //! The load's random walk per root second as a fraction of the largest |load| trained on:
  //! Q_L = (this x max |load|)^2 Ts.
  double load_walk = 0.01;
};

//! What fit_bidirectional_load_observer found.
struct BidirectionalObserverFit {
  estimation::BidirectionalLoadObserverParameters<double> parameters;  //!< priors + fitted values
  CurrentReference reference{};    //!< G and b_ref when every experiment has the command, else none
  BidirectionalNoiseRule rule{};   //!< the rule that set the variances
  std::vector<double> rmse;        //!< causal RMSE per experiment after the warm-up, load units
  double mean_rmse = 0.0;          //!< their mean
  double forward_fraction = 0.0;   //!< share of the samples moving forward
  double backward_fraction = 0.0;  //!< share of the samples moving back
  double forward_bias_rms = 0.0;   //!< RMS over the experiments of the forward inversion's bias
  double forward_mean_square = 0.0;   //!< per-sample mean square of the forward inversion's error
  double backward_mean_square = 0.0;  //!< the same, backward
  double peak_load = 0.0;             //!< max |load| over the training samples after the warm-up
};

//! The constants identify chooses for the observer by inner cross-validation
//! (choose_bidirectional_settings): the noise rule and five front-end settings.
struct BidirectionalSettings {
  BidirectionalNoiseRule rule{};     //!< the variances' rule
  double current_cutoff = 10.0;      //!< Hz, the current's low-pass
  double velocity_cutoff = 20.0;     //!< Hz, the velocity's low-pass
  double direction_scale = 0.05;     //!< rad, q0 of the direction state
  double velocity_threshold = 0.05;  //!< rad/s, slower is rest
  double stop_scale = 1.0;           //!< factor on the prior's stop thresholds (at most 1)
};

//! What choose_bidirectional_settings chose and why.
struct BidirectionalSelection {
  BidirectionalSettings settings{};  //!< the chosen constants
  //! The chosen settings' mean held-out RMSE over the inner folds, load units.
  double held_out_rmse = std::numeric_limits<double>::infinity();
  //! The same for the research note's constants (the prior's front end, the default rule).
  double prior_rmse = std::numeric_limits<double>::infinity();
  std::size_t candidates = 0;  //!< settings scored
  std::size_t folds = 0;       //!< inner folds (0: too few files, the priors kept)
};

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
//! rule.correlation_time / Ts (the inversion errors run in strokes, not white), the friction
//! prior (rule.friction_prior_scale x the RMS of the experiments' forward bias)^2, at least the
//! forward inversion's mean square, Q_L = (rule.load_walk max |load|)^2 Ts,
//! the initial load and its variance from the training loads. The filters, thresholds and stop
//! thresholds come from `prior`. Throws Error on empty or mismatched
//! data, a warm-up that is not finite and >= 0, fewer than 10 samples in either direction,
//! experiments all at one load level, a singular fit, a map whose gain would fall below a tenth
//! along the stroke, maps of opposite signs, or variances beyond the model's bound.
[[nodiscard]] ENDOHAPTICS_DECL BidirectionalObserverFit fit_bidirectional_load_observer(
    std::span<const LoadObserverData> data,
    const estimation::BidirectionalLoadObserverParameters<double>& prior, double warmup = 1.0,
    const BidirectionalNoiseRule& rule = {});

//! Sets the fit's variances by `rule` from its inversion statistics (as the fit does), and
//! fit.rule. Throws Error when a variance exceeds the model's bound.
ENDOHAPTICS_DECL void apply_noise_rule(BidirectionalObserverFit& fit,
                                       const BidirectionalNoiseRule& rule);

//! `prior` with the front-end settings of `s` (cut-offs, q0, velocity threshold, stop scale).
[[nodiscard]] ENDOHAPTICS_DECL estimation::BidirectionalLoadObserverParameters<double>
with_settings(const estimation::BidirectionalLoadObserverParameters<double>& prior,
              const BidirectionalSettings& s);

//! The front-end settings `prior` holds, with the default noise rule.
[[nodiscard]] ENDOHAPTICS_DECL BidirectionalSettings
settings_of(const estimation::BidirectionalLoadObserverParameters<double>& prior);

//! The noise rules step (1) of choose_bidirectional_settings scores, in order: correlation time
//! (outer) x friction prior scale x load walk (inner).
[[nodiscard]] ENDOHAPTICS_DECL std::vector<BidirectionalNoiseRule> noise_rule_grid();

//! Chooses the constants of BidirectionalSettings by cross-validation over `folds` (each a list
//! of indices into `data` held out together; all other experiments train it): the mean causal
//! RMSE of the held-out experiments after the warm-up, each held out once. The search: (1) the
//! noise rule on a grid (correlation time 0.05 to 0.8 s in steps of a factor sqrt(2), 9 values, x
//! friction prior scale 1, 2, 4, 8 x load walk 0.1, 0.3, 1, 3 % per root second: 144 rules) with
//! the prior's front end; (2) with that rule,
//! the front end one constant at a time, a factor of 2 up, else down, continued while the score
//! improves (at most 3 steps: the two cut-offs below Nyquist, q0, and the velocity threshold
//! when `vary_velocity_threshold`; the stop thresholds only narrower, at most 2 steps); a noise
//! constant whose best value lies on the grid's edge is walked beyond it the same way (factor 2,
//! 2, 3; at most 4 steps); (3) if the front end changed, the noise grid again on it. A candidate
//! whose fit fails on a fold loses. With fewer than two folds, or when every candidate fails, the
//! prior's front end and the default rule (folds 0). Deterministic; only `data` is looked at.
[[nodiscard]] ENDOHAPTICS_DECL BidirectionalSelection choose_bidirectional_settings(
    std::span<const LoadObserverData> data, const std::vector<std::vector<std::size_t>>& folds,
    const estimation::BidirectionalLoadObserverParameters<double>& prior, double warmup,
    bool vary_velocity_threshold = true);

//! The encoder's step, rad: the smallest nonzero position increment in `data`, when every nonzero
//! increment is a whole number of it (within 1 %: a quantised encoder read at every sample);
//! none when the data hold no motion or are not quantised (e.g. resampled by interpolation).
[[nodiscard]] ENDOHAPTICS_DECL std::optional<double> encoder_step(
    std::span<const LoadObserverData> data);

}  // namespace endohaptics::workflow

#if !defined(ENDOHAPTICS_SEPARATE_COMPILATION)
#include "endohaptics/workflow/impl/bidirectional_observer_fit.ipp"
#endif
