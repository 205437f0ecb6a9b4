//! @file
//! StallHold: a JointForceModel for cable-driven joints whose load shows in the motor current only
//! while the motor slides against it (docs/research_force_models.md, structure A1). While the
//! joint moves (|filtered velocity| > threshold) the held value follows the current beyond a dead
//! zone (the static friction of worksheet table 5.2); while it is stalled against an object the
//! value is held, because tendon stiction keeps the force while the current relaxes (2016
//! clamp-hits logs: the force stays at 7.6 N while the current decays from -0.97 A to -0.05 A).
//! A first-order lag then gives the output: force = gain x lag(held). Per step: three first-order
//! updates and a compare; noexcept, allocation-free. Units: A, rad/s, s; output in the gain's
//! unit (N or N m per A).
#pragma once

#include <Eigen/Core>
#include <cmath>
#include <cstdint>
#include <string>

#include "endohaptics/core/error.hpp"
#include "endohaptics/estimation/joint_force_model.hpp"
#include "endohaptics/model/state_space.hpp"

namespace endohaptics::estimation {

//! Which sign of current above the dead zone produces force.
enum class StallHoldSide : std::uint8_t {
  both,      //!< a signed dead zone: sign(i) max(0, |i| - c)
  positive,  //!< max(0, i - c): a load met only with positive current
  negative,  //!< min(0, i + c): a load met only with negative current (the 2016 clamps)
};

//! Parameters of StallHold. Defaults: the 2016 clamp (docs/research_force_models.md).
template <typename Scalar = double>
struct StallHoldParameters {
  Scalar current_deadzone = Scalar(0.20);        //!< A, c: static friction (table 5.2 clamp)
  Scalar velocity_threshold = Scalar(0.05);      //!< rad/s: at or below, stalled (value held)
  Scalar velocity_time_constant = Scalar(0.03);  //!< s, first-order low-pass of the velocity
  Scalar output_time_constant = Scalar(0.3);     //!< s, first-order lag of the output
  Scalar gain = Scalar(1);                       //!< output units per A beyond the dead zone
  StallHoldSide side = StallHoldSide::both;      //!< which current sign carries the load
  Scalar sample_time = Scalar(0.001);            //!< s, one advance()

  //! Throws Error naming the field, its value and the rule.
  void validate() const {
    auto require = [](bool ok, const char* field, Scalar value, const char* rule) {
      if (!ok) {
        ENDOHAPTICS_THROW(Error(std::string("StallHoldParameters: ") + field + " must be " + rule +
                                ", got " + endohaptics::detail::format_number(value)));
      }
    };
    const auto max = static_cast<Scalar>(max_joint_model_parameter);  // comparisons fail for NaN
    require(current_deadzone >= 0 && current_deadzone <= max, "current_deadzone", current_deadzone,
            "in [0, 1e6] A");
    require(velocity_threshold >= 0 && velocity_threshold <= max, "velocity_threshold",
            velocity_threshold, "in [0, 1e6] rad/s");
    require(velocity_time_constant >= 0 && velocity_time_constant <= max, "velocity_time_constant",
            velocity_time_constant, "in [0, 1e6] s");
    require(output_time_constant >= 0 && output_time_constant <= max, "output_time_constant",
            output_time_constant, "in [0, 1e6] s");
    require(std::fabs(gain) <= max, "gain", gain, "in [-1e6, 1e6]");
    require(std::isfinite(sample_time) && sample_time > 0, "sample_time", sample_time,
            "finite and > 0 s");
  }
};

//! The stall-hold force model (see the file comment). State: (filtered velocity rad/s, held
//! current beyond the dead zone A, lagged held value A); the force is gain x the third.
template <typename Scalar = double>
class StallHold {
 public:
  using ScalarType = Scalar;                       //!< floating-point type
  using State = Eigen::Matrix<Scalar, 3, 1>;       //!< (velocity, held, lagged)
  using Parameters = StallHoldParameters<Scalar>;  //!< the model's parameters
  using Signals = JointSignals<Scalar>;            //!< one joint's signals for one tick

  //! Validates `p` (throws Error naming the field); the state starts at zero.
  explicit StallHold(const Parameters& p = {}) : p_((p.validate(), p)) {
    alpha_v_ = p_.sample_time / (p_.velocity_time_constant + p_.sample_time);
    alpha_o_ = p_.sample_time / (p_.output_time_constant + p_.sample_time);
  }

  [[nodiscard]] const Parameters& parameters() const noexcept { return p_; }    //!< as given
  [[nodiscard]] Scalar sample_time() const noexcept { return p_.sample_time; }  //!< s
  //! False: the output is a state.
  [[nodiscard]] bool memoryless() const noexcept { return false; }
  //! gain x the lagged held value (no feedthrough from `s`).
  [[nodiscard]] Scalar force(const Signals&) const noexcept { return p_.gain * x_[2]; }

  //! One sample_time: filters the velocity, updates the held value while the joint moves, lags
  //! it. Non-finite signals: state untouched, StepStatus::non_finite_input.
  model::StepStatus advance(const Signals& s) noexcept {
    if (!std::isfinite(s.current) || !std::isfinite(s.velocity)) {
      return model::StepStatus::non_finite_input;
    }
    State next = x_;
    next[0] += alpha_v_ * (s.velocity - next[0]);
    if (std::fabs(next[0]) > p_.velocity_threshold) next[1] = beyond_deadzone(s.current);
    next[2] += alpha_o_ * (next[1] - next[2]);
    if (!next.allFinite()) return model::StepStatus::non_finite_result;
    x_ = next;
    return model::StepStatus::ok;
  }

  [[nodiscard]] const State& state() const noexcept { return x_; }  //!< (velocity, held, lagged)
  //! Sets the state (e.g. zero, or a previous state()).
  void reset(const State& x = State::Zero()) noexcept { x_ = x; }

  //! The current beyond the dead zone on the loaded side (A), what the held value follows.
  [[nodiscard]] Scalar beyond_deadzone(Scalar current) const noexcept {
    const Scalar c = p_.current_deadzone;
    switch (p_.side) {
      case StallHoldSide::positive:
        return current > c ? current - c : Scalar(0);
      case StallHoldSide::negative:
        return current < -c ? current + c : Scalar(0);
      case StallHoldSide::both:
        break;
    }
    return current > c ? current - c : (current < -c ? current + c : Scalar(0));
  }

 private:
  Parameters p_;
  Scalar alpha_v_{};
  Scalar alpha_o_{};
  State x_ = State::Zero();
};

static_assert(JointForceModel<StallHold<double>>);

}  // namespace endohaptics::estimation
