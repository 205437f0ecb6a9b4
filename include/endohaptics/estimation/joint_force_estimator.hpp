//! @file
//! The `JointForceEstimator` concept: what a TeleopLoop asks of a force estimator (worksheet 5.1,
//! figure 5.2: measured motor state -> external force per motor), the motor-order vector types it
//! speaks in (protocol/motor_order.hpp), and `NoForceEstimator`. Forces in the joint's unit
//! (N for the clamp and pitch models, N m for roll), motor order.
#pragma once

#include <Eigen/Core>
#include <concepts>

#include "endohaptics/protocol/motor_order.hpp"
#include "endohaptics/protocol/packet_codec.hpp"

namespace endohaptics::estimation {

//! One value per EndoWrist motor, in motor order (protocol::Motor).
using MotorVector = Eigen::Matrix<double, protocol::endowrist_motors, 1>;
//! A decoded sbRIO state of the EndoWrist's four motors.
using MotorState4 = protocol::MotorState<protocol::endowrist_motors>;

//! Estimates the external force on each motor from the measured state and the setpoint that was
//! sent. `estimate` returns true when `force` was written with finite values; `reset` forgets the
//! history (called when the link comes back).
template <typename E>
concept JointForceEstimator = requires(E& estimator, const MotorState4& measured,
                                       const MotorVector& setpoint, MotorVector& force) {
  { estimator.estimate(measured, setpoint, force) }
  noexcept->std::convertible_to<bool>;
  { estimator.reset() }
  noexcept;
};

//! No estimation: zero force (useful to run position control only, and in tests).
struct NoForceEstimator {
  //! Writes zero force; always succeeds.
  bool estimate(const MotorState4&, const MotorVector&, MotorVector& force) noexcept {
    force.setZero();
    return true;
  }
  //! Nothing to forget.
  void reset() noexcept {}
};

static_assert(JointForceEstimator<NoForceEstimator>);

}  // namespace endohaptics::estimation
