//! @file
//! fit_push_load_observer: identifies estimation::PushLoadObserver from logs by two linear least
//! squares (docs/research_force_models.md, K2): (a) on the push-regime samples, the filtered
//! current on [load, 1, filtered velocity] gives c_p, d_p, b_p and the residual variance R_p;
//! (b) with those, the observer runs causally on every experiment and (load - estimate) on
//! [g, g estimate], g = (1 - regime) / 2, gives the load-side friction map e0, e1. Beside (a), the
//! same least squares on the back-driven samples gives the map used before the first push (c_b,
//! d_b, b_b and the mean square error of its inversion); the stiffness k_q is the value of a grid
//! with the best causal training score. When every experiment carries the commanded current, the
//! measured current is first referred to it (estimation/current_offset_reference.hpp): G by least
//! squares within each experiment, b_ref the experiments' mean offset. Every
//! experiment weighs the same (its normal equations divided by its length); a warm-up at the start
//! of each is left out. Configuration time: allocates, throws endohaptics::Error.
#pragma once

#include <Eigen/Dense>
#include <cmath>
#include <limits>
#include <optional>
#include <span>
#include <string>
#include <vector>
#include "endohaptics/core/separate_compilation.hpp"

#include "endohaptics/core/error.hpp"
#include "endohaptics/estimation/current_offset_reference.hpp"
#include "endohaptics/estimation/push_load_observer.hpp"
#include "endohaptics/estimation/simulate.hpp"

namespace endohaptics::workflow {

//! One experiment on the model's uniform grid (sample_time apart).
struct LoadObserverData {
  Eigen::VectorXd current;   //!< A
  Eigen::VectorXd position;  //!< rad (only its increments are used)
  Eigen::VectorXd load;      //!< the truth (e.g. grip torque, mN m)
  Eigen::VectorXd command;   //!< the commanded current, any unit (empty: not logged)
};

//! The offset reference of the current, when the data carry the command.
using CurrentReference = std::optional<estimation::CurrentOffsetReferenceParameters<double>>;

//! What fit_push_load_observer found.
struct LoadObserverFit {
  estimation::PushLoadObserverParameters<double> parameters;  //!< priors plus the fitted values
  CurrentReference reference{};  //!< G and b_ref when every experiment has the command, else none
  std::vector<double> rmse;      //!< causal RMSE per experiment after the warm-up, load units
  double mean_rmse = 0.0;        //!< their mean
  double push_fraction = 0.0;    //!< share of the samples in the push regime
};

//! The experiment's current referred to its command by `reference` (causal, from the first
//! sample), or as measured without a reference. Throws Error naming `where` when the experiment
//! lacks the command or a sample is not finite.
[[nodiscard]] ENDOHAPTICS_DECL Eigen::VectorXd referred_current(const LoadObserverData& d,
                                                                const CurrentReference& reference,
                                                                const char* where);

//! Throws Error naming `where` and the experiment unless every experiment's current, position and
//! load have the same length, longer than `skip` + 1 samples (the warm-up).
ENDOHAPTICS_DECL void check_experiments(std::span<const LoadObserverData> data, Eigen::Index skip,
                                        const char* where);

//! The experiments with their current referred to the command by `reference` (for a fit that
//! works on the current as the fitted model will see it); empty without a reference (then use the
//! experiments as measured). Throws Error as referred_current.
[[nodiscard]] ENDOHAPTICS_DECL std::vector<LoadObserverData> referred_experiments(
    std::span<const LoadObserverData> data, const CurrentReference& reference, const char* where);

namespace detail {
//! The causal output of an observer `model` (PushLoadObserver, BidirectionalLoadObserver) from its
//! reset state on one experiment: estimation::simulate on the (referred) current and the encoder
//! angle. Throws Error naming `where` and the sample when a step fails.
template <typename Observer>
[[nodiscard]] Eigen::VectorXd simulate_observer(const Observer& model, const LoadObserverData& d,
                                                const CurrentReference& reference,
                                                const char* where) {
  Observer m = model;
  m.reset();
  const Eigen::VectorXd current = referred_current(d, reference, where);
  Eigen::VectorXd y(d.current.size());
  const estimation::SimulationResult r = estimation::simulate(
      m,
      [&](Eigen::Index k) noexcept {
        return estimation::JointSignals<double>{d.position[k], 0.0, current[k], 0.0};
      },
      y);
  if (!r.ok()) {
    ENDOHAPTICS_THROW(Error(std::string(where) + ": non-finite signal or result at sample " +
                            std::to_string(r.sample)));
  }
  return y;
}
}  // namespace detail

//! The causal output of `model` (from its reset state) on one experiment; with a `reference`, the
//! current referred to the command first (the experiment must then carry it).
[[nodiscard]] ENDOHAPTICS_DECL Eigen::VectorXd simulate_load_observer(
    const estimation::PushLoadObserver<double>& model, const LoadObserverData& d,
    const CurrentReference& reference = std::nullopt);

//! RMSE of `model` on each experiment after `warmup` s (causal: state from reset, no load used).
[[nodiscard]] ENDOHAPTICS_DECL std::vector<double> load_observer_rmse(
    const estimation::PushLoadObserver<double>& model, std::span<const LoadObserverData> data,
    double warmup, const CurrentReference& reference = std::nullopt);

//! G and b_ref of the current's offset reference from experiments that all carry the command: G
//! by least squares of the current on the command within each experiment (each its own
//! intercept, each weighing the same), b_ref the mean over the experiments of their mean of
//! current - G command. None when an experiment has no command, the command does not vary, or G
//! or b_ref is not finite or out of the model file's bounds (|G| in [1e-9, 1e6], |b_ref| <= 1e6).
[[nodiscard]] ENDOHAPTICS_DECL CurrentReference
fit_current_reference(std::span<const LoadObserverData> data);

//! Fits the current's offset reference (when the data carry the command), c_p, d_p, b_p, R_p, the
//! initial load (the training mean), the back-driven map, k_q and e0, e1 (see the file comment);
//! the filters, thresholds, push sign, Q and P0 come from `prior`. Throws Error on empty or
//! mismatched data, too few push samples, or a singular fit.
[[nodiscard]] ENDOHAPTICS_DECL LoadObserverFit fit_push_load_observer(
    std::span<const LoadObserverData> data,
    const estimation::PushLoadObserverParameters<double>& prior, double warmup = 1.0);

}  // namespace endohaptics::workflow

#if !defined(ENDOHAPTICS_SEPARATE_COMPILATION)
#include "endohaptics/workflow/impl/push_load_observer_fit.ipp"
#endif
