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
#include <array>
#include <cmath>
#include <cstdint>
#include <string>
#include <string_view>
#include <utility>

#include "endohaptics/core/error.hpp"
#include "endohaptics/core/parameter.hpp"
#include "endohaptics/estimation/joint_force_model.hpp"
#include "endohaptics/model/state_space.hpp"

namespace endohaptics::estimation {

//! Which sign of current above the dead zone produces force.
enum class StallHoldSide : std::uint8_t {
  both,      //!< a signed dead zone: sign(i) max(0, |i| - c)
  positive,  //!< max(0, i - c): a load met only with positive current
  negative,  //!< min(0, i + c): a load met only with negative current (the 2016 clamps)
};

//! The names of StallHoldSide ("both", "positive", "negative"), for files and messages.
[[nodiscard]] constexpr std::array<std::pair<std::string_view, StallHoldSide>, 3> enumerators(
    StallHoldSide) noexcept {
  return {{{"both", StallHoldSide::both},
           {"positive", StallHoldSide::positive},
           {"negative", StallHoldSide::negative}}};
}

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

  //! Every parameter but the sample time, by its file name, with its bound: `v(name, field,
  //! Bound)` for each (core/parameter.hpp). The one list validate() and the model files use.
  template <typename Self, typename Visitor>
  static void for_each_field(Self& p, Visitor&& v) {
    constexpr double max = max_joint_model_parameter;
    v("current_deadzone", p.current_deadzone, Bound::in(0, max, "A"));
    v("velocity_threshold", p.velocity_threshold, Bound::in(0, max, "rad/s"));
    v("velocity_time_constant", p.velocity_time_constant, Bound::in(0, max, "s"));
    v("output_time_constant", p.output_time_constant, Bound::in(0, max, "s"));
    v("gain", p.gain, Bound::in(-max, max));
    v("side", p.side, Bound{});
  }

  //! Throws ParameterError naming the field, its value and the rule.
  void validate() const {
    const ParameterChecker check{"StallHoldParameters"};
    check("sample_time", sample_time, sample_time_bound);
    for_each_field(*this, check);
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
  //! it. Non-finite signals: state untouched, NumericStatus::non_finite_input.
  model::NumericStatus advance(const Signals& s) noexcept {
    if (!std::isfinite(s.current) || !std::isfinite(s.velocity)) {
      return model::NumericStatus::non_finite_input;
    }
    State next = x_;
    next[0] += alpha_v_ * (s.velocity - next[0]);
    if (std::fabs(next[0]) > p_.velocity_threshold) next[1] = beyond_deadzone(s.current);
    next[2] += alpha_o_ * (next[1] - next[2]);
    if (!next.allFinite()) return model::NumericStatus::non_finite_result;
    x_ = next;
    return model::NumericStatus::ok;
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
