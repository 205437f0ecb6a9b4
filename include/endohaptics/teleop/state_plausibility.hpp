//! @file
//! StatePlausibility: is a decoded state packet something the EndoWrist's motors can report?
//! A state that passed the codec (right size, finite, valid mask) can still be impossible: a
//! position far outside the joint's range, a velocity or a current beyond what the motor and its
//! ESCON 50/5 controller can produce (worksheet 2.4, 2.5.2), or a jump no motor makes in the time
//! since the last plausible state. The TeleopLoop never follows such a state: it is a fault
//! (docs/architecture.md, "Safety envelope"). Units: rad (motor side, after gearing), rad/s, A, s.
#pragma once

#include <Eigen/Core>
#include <cmath>
#include <cstdint>
#include <string>
#include <string_view>

#include "endohaptics/core/error.hpp"
#include "endohaptics/core/parameter.hpp"
#include "endohaptics/protocol/packet_codec.hpp"

namespace endohaptics::teleop {

//! Why a decoded state was refused; `none` when it is plausible.
enum class StateFault : std::uint8_t {
  none = 0,
  position_out_of_range,  //!< a position outside [lower - margin, upper + margin]
  velocity_out_of_range,  //!< |velocity| above max_velocity
  current_out_of_range,   //!< |current| above max_current
  position_jump,          //!< moved further than max_velocity allows since the last good state
};

//! Number of StateFault values (for per-cause counters).
inline constexpr int state_fault_count = 5;

//! The fault's name for logs ("none", "position out of range", ...).
[[nodiscard]] constexpr std::string_view to_string(StateFault f) noexcept {
  switch (f) {
    case StateFault::none:
      return "none";
    case StateFault::position_out_of_range:
      return "position out of range";
    case StateFault::velocity_out_of_range:
      return "velocity out of range";
    case StateFault::current_out_of_range:
      return "current out of range";
    case StateFault::position_jump:
      return "position jump";
  }
  return "unknown fault";
}

//! Physical bounds of the plausibility check (the largest values `validate` accepts).
struct PlausibilityBounds {
  //! rad/s at the gear output: the maxon A-max 22 at the full 24 V supply with no load turns
  //! 24 V / 0.0171 V s/rad = 1404 rad/s, 37.8 rad/s after the 37.1:1 gearhead (sim/ defaults).
  static constexpr double max_velocity = 40.0;
  //! A: the ESCON 50/5's peak output current (datasheet; the rig's limit is 2 A, table 5.3).
  static constexpr double max_current = 15.0;
  static constexpr double max_margin = 0.5;  //!< rad: position_margin and jump_tolerance
};

//! Bounds a plausible state respects. Defaults: the hardware's limits (PlausibilityBounds).
struct StatePlausibility {
  double position_margin = 0.2;  //!< rad a reported position may lie outside the joint range
  double max_velocity = 40.0;    //!< rad/s, per motor (gear output)
  double max_current = 15.0;     //!< A, per motor
  double jump_tolerance = 0.05;  //!< rad on top of max_velocity x elapsed (encoder, play)

  //! Every field by its configuration name, with its bound (core/parameter.hpp).
  template <typename Self, typename Visitor>
  static void for_each_field(Self& p, Visitor&& v) {
    using B = PlausibilityBounds;
    v("position_margin", p.position_margin, Bound::in(0, B::max_margin, "rad"));
    v("max_velocity", p.max_velocity, Bound::above(0, B::max_velocity, "rad/s"));
    v("max_current", p.max_current, Bound::above(0, B::max_current, "A"));
    v("jump_tolerance", p.jump_tolerance, Bound::in(0, B::max_margin, "rad"));
  }

  //! Throws ParameterError naming the field, its value and the allowed range.
  void validate() const { for_each_field(*this, ParameterChecker{"StatePlausibility"}); }

  //! The first fault of `state` (checked in the order of StateFault), or StateFault::none.
  //! `lower`/`upper`: the joint range, rad, motor order. `previous`: the last plausible state,
  //! received `elapsed` seconds ago (nullptr: none yet, no jump check). Finite inputs assumed
  //! (the codec refuses NaN and Inf); a NaN still fails every comparison and is refused.
  template <int N>
  [[nodiscard]] StateFault check(const protocol::MotorState<N>& state,
                                 const Eigen::Matrix<double, N, 1>& lower,
                                 const Eigen::Matrix<double, N, 1>& upper,
                                 const protocol::MotorState<N>* previous,
                                 double elapsed) const noexcept {
    for (int i = 0; i < N; ++i) {
      const double p = state.position[i];
      if (!(p >= lower[i] - position_margin && p <= upper[i] + position_margin)) {
        return StateFault::position_out_of_range;
      }
    }
    for (int i = 0; i < N; ++i) {
      if (!(std::fabs(state.velocity[i]) <= max_velocity)) return StateFault::velocity_out_of_range;
    }
    for (int i = 0; i < N; ++i) {
      if (!(std::fabs(state.current[i]) <= max_current)) return StateFault::current_out_of_range;
    }
    if (previous != nullptr) {
      const double reach = max_velocity * std::fmax(elapsed, 0.0) + jump_tolerance;
      for (int i = 0; i < N; ++i) {
        if (!(std::fabs(state.position[i] - previous->position[i]) <= reach)) {
          return StateFault::position_jump;
        }
      }
    }
    return StateFault::none;
  }
};

}  // namespace endohaptics::teleop
