//! @file
//! The emulator's truth log (endohaptics-sbrio-emulator --truth-log), one CSV row per period:
//! time (s, CLOCK_MONOTONIC), enable and active masks, setpoints (rad), the true joint positions
//! (rad), velocities (rad/s), currents (A) and external forces (N, along +setpoint: the
//! convention of the estimate in the bridge's tick log), then what the sbRIO reports (position,
//! velocity, filtered current): the inputs a force model sees beside the truth it should give.
//! Formatting allocates: not for a tick.
#pragma once

#include <cstdio>
#include <string>
#include <string_view>

#include "endohaptics/protocol/packet_codec.hpp"
#include "endohaptics/sim/simulated_rig.hpp"

namespace endohaptics::sim {

//! The header line (with its newline), the columns of truth_log_row for 4 motors.
inline constexpr std::string_view truth_log_header =
    "time,enable_mask,active_mask,setpoint0,setpoint1,setpoint2,setpoint3,"
    "position0,position1,position2,position3,velocity0,velocity1,velocity2,velocity3,"
    "current0,current1,current2,current3,force0,force1,force2,force3,"
    "reported_position0,reported_position1,reported_position2,reported_position3,"
    "reported_velocity0,reported_velocity1,reported_velocity2,reported_velocity3,"
    "reported_current0,reported_current1,reported_current2,reported_current3\n";

//! One row (with its newline) at `seconds`: the setpoint obeyed, the rig's truth and the state
//! it reports. Time with 9 decimals, every other number in 7 significant digits.
[[nodiscard]] inline std::string truth_log_row(double seconds,
                                               const protocol::MotorSetpoint<4>& setpoint,
                                               const RigTruth<4>& truth,
                                               const protocol::MotorState<4>& reported) {
  char field[64];
  std::snprintf(field, sizeof field, "%.9f,%u,%u", seconds,
                static_cast<unsigned>(setpoint.enable_mask),
                static_cast<unsigned>(reported.active_mask));
  std::string row = field;
  const auto add = [&](const Eigen::Matrix<double, 4, 1>& v) {
    for (int i = 0; i < 4; ++i) {
      std::snprintf(field, sizeof field, ",%.7g", v[i]);
      row += field;
    }
  };
  add(setpoint.position);
  add(truth.joint_position);
  add(truth.motor_velocity);
  add(truth.motor_current);
  add(truth.external_force);
  add(reported.position);
  add(reported.velocity);
  add(reported.current);
  row += '\n';
  return row;
}

}  // namespace endohaptics::sim
