//! @file
//! `NumericStatus`: the one outcome of every real-time numeric step (a model's tick, a filter's
//! predict/update, a mapping, forward kinematics, the force estimate). Each step either did its
//! work (`ok`) or found a non-finite value and left its outputs and state as they were, so a
//! caller can hold the last good value; which values a step checks is said where it is declared.
#pragma once

#include <cstdint>
#include <string_view>

namespace endohaptics {

//! Outcome of a real-time numeric step. On anything but `ok` the step's outputs and state are
//! left untouched (a step that replaces a bad input instead, such as the human arm model, says
//! so where it is declared).
enum class NumericStatus : std::uint8_t {
  ok = 0,
  non_finite_input,  //!< NaN or +-Inf in an input (a vector, a joint state, a force, a motion)
  non_finite_measurement,  //!< NaN or +-Inf in a measurement (a Kalman filter's z)
  non_finite_result,       //!< finite input, but the result overflowed (a diverging model)
};

//! The status's name for logs: "ok", "non-finite input", "non-finite measurement",
//! "non-finite result".
[[nodiscard]] constexpr std::string_view to_string(NumericStatus status) noexcept {
  switch (status) {
    case NumericStatus::ok:
      return "ok";
    case NumericStatus::non_finite_input:
      return "non-finite input";
    case NumericStatus::non_finite_measurement:
      return "non-finite measurement";
    case NumericStatus::non_finite_result:
      return "non-finite result";
  }
  return "unknown";
}

}  // namespace endohaptics
