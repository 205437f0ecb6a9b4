//! @file
//! The EndoWrist's motor order as the sbRIO numbers its motors (worksheet 3.2.2, figure 3.4:
//! index 0..3 of every vector in a packet): roll, pitch, clamp1, clamp2. Every "per motor"
//! vector of the library (setpoints, measured state, estimated forces) is in this order.
#pragma once

#include <cstdint>
#include <string_view>

namespace endohaptics::protocol {

//! The motors of one EndoWrist; the value is the index into motor-order vectors.
enum class Motor : std::uint8_t { roll = 0, pitch = 1, clamp1 = 2, clamp2 = 3 };

//! Motors of one EndoWrist (the 2016 rig drives four of the sbRIO's seven channels).
inline constexpr int endowrist_motors = 4;

//! rad: every joint of the EndoWrist stays in [-endowrist_joint_range, endowrist_joint_range]
//! (motor side; the +-1.028 rad of the 2016 tuning logs): the default range of everything that
//! guards a setpoint (teleop::SafetyConfig, kinematics::CylindricalMapperConfig,
//! transport::GatewayConfig).
inline constexpr double endowrist_joint_range = 1.028;
//! rad/s per joint (motor side): the tool cannot go faster; the default setpoint rate limit
//! (teleop::SafetyConfig, transport::GatewayConfig).
inline constexpr double endowrist_max_joint_rate = 4.0;

//! Human-readable name of a motor.
[[nodiscard]] constexpr std::string_view to_string(Motor motor) noexcept {
  switch (motor) {
    case Motor::roll:
      return "roll";
    case Motor::pitch:
      return "pitch";
    case Motor::clamp1:
      return "clamp1";
    case Motor::clamp2:
      return "clamp2";
  }
  return "unknown motor";
}

}  // namespace endohaptics::protocol
