//! @file
//! CurrentOffsetReference: the measured motor current referred to the commanded current. A
//! current-mode amplifier makes the motor current follow its command, i = G u + b; the offset b of
//! the current measurement changes between sessions (on the UMN grasper by 0.015 A, the size of
//! the sessions' push-current offset: docs/research_force_models.md, K6) while G does not. The
//! correction i' = i - (b_hat - b_ref) moves every session's measurement to the training
//! sessions' offset b_ref, with b_hat the running mean of i - G u since the start (causal: inputs
//! only). A few flops per step; noexcept, allocation-free. Units: A; the command in its own unit
//! (G in A per command unit).
#pragma once

#include <Eigen/Core>
#include <cmath>
#include <string>

#include "endohaptics/core/error.hpp"
#include "endohaptics/core/parameter.hpp"
#include "endohaptics/model/joint_model_bounds.hpp"
#include "endohaptics/model/state_space.hpp"

namespace endohaptics::estimation {

//! Parameters of CurrentOffsetReference, from fit_current_reference
//! (workflow/push_load_observer_fit.hpp).
template <typename Scalar = double>
struct CurrentOffsetReferenceParameters {
  Scalar command_gain = Scalar(1);      //!< G, A per command unit, non-zero
  Scalar reference_offset = Scalar(0);  //!< b_ref, A: the training runs' mean of i - G u

  //! Both parameters by their file names, with their bounds (core/parameter.hpp).
  template <typename Self, typename Visitor>
  static void for_each_field(Self& p, Visitor&& v) {
    constexpr double max = model::max_joint_model_parameter;
    v("command_gain", p.command_gain, Bound::magnitude(model::min_current_per_load, max));
    v("reference_offset", p.reference_offset, Bound::in(-max, max));
  }

  //! Throws ParameterError naming the field, its value and the rule.
  void validate() const {
    for_each_field(*this, ParameterChecker{"CurrentOffsetReferenceParameters"});
  }
};

//! The running offset correction (see the file comment).
template <typename Scalar = double>
class CurrentOffsetReference {
 public:
  using Parameters = CurrentOffsetReferenceParameters<Scalar>;  //!< its parameters
  using State = Eigen::Matrix<Scalar, 2, 1>;  //!< (running mean of i - G u, samples so far)

  //! Validates `p` (throws Error naming the field).
  explicit CurrentOffsetReference(const Parameters& p = {}) : p_((p.validate(), p)) {}

  [[nodiscard]] const Parameters& parameters() const noexcept { return p_; }  //!< as given

  //! One sample: the measured current `current` (A) and the command `command`. Non-finite input:
  //! state untouched, NumericStatus::non_finite_input (corrected() then still gives the last
  //! value).
  [[nodiscard]] model::NumericStatus advance(Scalar current, Scalar command) noexcept {
    if (!std::isfinite(current) || !std::isfinite(command)) {
      return model::NumericStatus::non_finite_input;
    }
    State x = x_;
    x[1] += Scalar(1);
    x[0] += (current - p_.command_gain * command - x[0]) / x[1];
    const Scalar corrected = current - (x[0] - p_.reference_offset);
    if (!x.allFinite() || !std::isfinite(corrected)) return model::NumericStatus::non_finite_result;
    x_ = x;
    corrected_ = corrected;
    return model::NumericStatus::ok;
  }
  //! The last sample's current referred to the training offset, A.
  [[nodiscard]] Scalar corrected() const noexcept { return corrected_; }
  //! The running offset estimate b_hat, A (0 before the first sample).
  [[nodiscard]] Scalar offset() const noexcept { return x_[0]; }

  [[nodiscard]] const State& state() const noexcept { return x_; }  //!< see State
  void reset(const State& x) noexcept { x_ = x; }                   //!< sets the state
  void reset() noexcept {                                           //!< no samples yet
    x_.setZero();
    corrected_ = Scalar(0);
  }

 private:
  Parameters p_;
  State x_ = State::Zero();
  Scalar corrected_{};
};

}  // namespace endohaptics::estimation
