//! @file
//! simulate: a JointForceModel run over a recorded segment, one advance() and one force() per
//! sample, the loop every offline replay and fit shares (workflow's simulate_stall_hold,
//! simulate_load_observer, simulate_bidirectional_observer, simulate_joint_model). Units: the
//! model's. noexcept and allocation-free given an output vector of the segment's length.
#pragma once

#include <Eigen/Core>
#include <concepts>

#include "endohaptics/estimation/joint_force_model.hpp"
#include "endohaptics/model/state_space.hpp"

namespace endohaptics::estimation {

//! What simulate did: every sample (NumericStatus::ok, sample -1), or the first sample whose
//! advance() failed and its status (the outputs from it on are not written).
struct SimulationResult {
  model::NumericStatus status = model::NumericStatus::ok;  //!< the failing step's status, or ok
  Eigen::Index sample = -1;                                //!< the failing sample, or -1
  //! True when every sample ran.
  [[nodiscard]] bool ok() const noexcept { return status == model::NumericStatus::ok; }
};

//! Runs `model` from its current state over `y.size()` samples: for each k, s = signals(k), then
//! advance(s) and y[k] = force(s) (the force after the step, as the estimator reads it). Stops at
//! the first step that fails (non-finite signal or result), leaving the model as that step did
//! (all-or-nothing: untouched) and returning the sample.
template <JointForceModel M, typename SignalsAt>
requires std::invocable<SignalsAt&, Eigen::Index>
[[nodiscard]] SimulationResult simulate(
    M& model, SignalsAt&& signals,
    Eigen::Ref<Eigen::Matrix<typename M::ScalarType, Eigen::Dynamic, 1>>
        y) noexcept(noexcept(signals(Eigen::Index{}))) {
  for (Eigen::Index k = 0; k < y.size(); ++k) {
    const JointSignals<typename M::ScalarType> s = signals(k);
    const model::NumericStatus status = model.advance(s);
    if (status != model::NumericStatus::ok) return {status, k};
    y[k] = model.force(s);
  }
  return {};
}

}  // namespace endohaptics::estimation
