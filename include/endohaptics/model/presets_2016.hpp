//! @file
//! The 2016 EndoWrist force models, worksheet appendix C: yaw force (eqs. C.1-C.3) and pitch
//! force (C.4-C.6), both u = [motor current A; motor velocity rad/s] -> force, D = 0, Ts = 0.02 s;
//! a placeholder static roll-torque gain (appendix E.1.3, figure E.8 data, N m/A); and the yaw
//! model with the table 5.2 static-friction dead zone on the current. See
//! docs/models/presets_2016.md.
#pragma once

#include <Eigen/Core>
#include <array>

#include "endohaptics/model/hammerstein_wiener.hpp"
#include "endohaptics/model/state_space.hpp"
#include "endohaptics/model/static_nonlinearity.hpp"

namespace endohaptics::model {

//! Sample time the appendix C models were identified at (the logs' 50 Hz; the 2016 code's T), s.
inline constexpr double sample_time_2016 = 0.02;

//! Static friction current of the yaw motor, table 5.2, A.
inline constexpr double yaw_static_friction_2016 = 0.21;
//! Static friction current of the clamp motor, table 5.2, A.
inline constexpr double clamp_static_friction_2016 = 0.20;

//! Roll torque per roll-motor current, N m/A. PLACEHOLDER: the worksheet gives no number; this is
//! the least-squares slope through the origin of the 39 points behind figure E.8 (0.07008).
inline constexpr double roll_torque_gain_2016 = 0.070;

//! Yaw (grip) force model, eqs. C.1-C.3: 6 states, u = [current A; velocity rad/s], y = force
//! (N as far as the logs tell, see the doc), D = 0, Ts = 0.02 s. Entries as printed (4 decimals).
template <typename Scalar = double>
[[nodiscard]] StateSpace<6, 2, 1, Scalar> yaw_force_2016() {
  using SS = StateSpace<6, 2, 1, Scalar>;
  const Eigen::Matrix<double, 6, 6> A{{0.9745, -0.3699, -0.0620, 0.2917, 0.5007, -5.5391},
                                      {-0.0002, 1.0135, 0.8285, -0.3743, -1.4557, -2.0967},
                                      {-0.0002, -0.0123, 0.9149, -1.1440, -0.9316, -2.7853},
                                      {-0.0001, -0.0002, 0.0275, 0.7842, 1.6365, 1.8560},
                                      {0.0000, -0.0001, -0.0019, -0.0809, 0.8869, 2.4092},
                                      {0.0000, -0.0000, 0.0001, 0.0080, -0.0583, 0.8887}};
  const Eigen::Matrix<double, 6, 2> B{{1.9790, 0.0335}, {-2.4107, 0.9244}, {12.9892, -0.8068},
                                      {0.0178, 0.3667}, {1.8671, -0.1057}, {-0.0295, -0.0104}};
  const Eigen::Matrix<double, 1, 6> C{{-0.3687, -0.4929, 0.5447, 0.4463, -0.2808, 0.1893}};
  return SS(A.cast<Scalar>(), B.cast<Scalar>(), C.cast<Scalar>(), SS::MatrixD::Zero(),
            static_cast<Scalar>(sample_time_2016));
}

//! Pitch force model, eqs. C.4-C.6 (B carries the printed 10^4 factor): 6 states,
//! u = [current A; velocity rad/s], y = force (gram-force as far as the logs tell, see the doc),
//! D = 0, Ts = 0.02 s.
template <typename Scalar = double>
[[nodiscard]] StateSpace<6, 2, 1, Scalar> pitch_force_2016() {
  using SS = StateSpace<6, 2, 1, Scalar>;
  const Eigen::Matrix<double, 6, 6> A{{0.9546, -0.3739, -0.1507, -0.7514, 0.4866, -4.3793},
                                      {0.0144, 1.0017, -0.4851, 1.5654, -0.6023, 6.5551},
                                      {0.0015, 0.0096, 0.8208, -0.2425, -0.4349, -4.8771},
                                      {0.0001, -0.0026, -0.0708, 0.7185, -0.8808, -0.0027},
                                      {0.0000, 0.0006, 0.0861, 0.1456, -0.4513, 0.7099},
                                      {0.0000, -0.0004, 0.0179, -0.0745, -0.0216, 0.7915}};
  // Printed as [...] * 10^4 (C.5); multiplied out here so every entry is an exact integer.
  const Eigen::Matrix<double, 6, 2> B{{27203, -934},  {-51162, 1742}, {50941, -1705},
                                      {35189, -1129}, {17066, -474},  {3376, -111}};
  const Eigen::Matrix<double, 1, 6> C{{-0.3860, -0.4915, -0.4790, 0.3761, -0.1281, -0.3845}};
  return SS(A.cast<Scalar>(), B.cast<Scalar>(), C.cast<Scalar>(), SS::MatrixD::Zero(),
            static_cast<Scalar>(sample_time_2016));
}

//! Roll torque as a static gain (worksheet 4.3: "a state that only depends on input"):
//! y = gain * u, u = roll current A, y = torque N m; A = B = C = 0, D = gain, Ts = 0.02 s.
//! Throws Error on a non-finite gain. The default gain is a placeholder (see above).
template <typename Scalar = double>
[[nodiscard]] StateSpace<1, 1, 1, Scalar> roll_torque_2016(
    Scalar gain = static_cast<Scalar>(roll_torque_gain_2016)) {
  using SS = StateSpace<1, 1, 1, Scalar>;
  return SS(SS::MatrixA::Zero(), SS::MatrixB::Zero(), SS::MatrixC::Zero(),
            SS::MatrixD::Constant(gain), static_cast<Scalar>(sample_time_2016));
}

//! The yaw preset as a Hammerstein model: a dead zone on the current (u0), none on velocity.
template <typename Scalar = double>
using YawForceHW2016 =
    HammersteinWiener<StateSpace<6, 2, 1, Scalar>, PerChannel<Deadzone<Scalar>, 2>>;

//! `yaw_force_2016()` behind a symmetric current dead zone of +-`current_deadzone` A (default:
//! the yaw static friction of table 5.2, 0.21 A; pass `clamp_static_friction_2016` for 0.20 A).
//! Velocity passes unchanged. Throws Error unless the width is finite and >= 0.
template <typename Scalar = double>
[[nodiscard]] YawForceHW2016<Scalar> yaw_force_2016_hw(
    Scalar current_deadzone = static_cast<Scalar>(yaw_static_friction_2016)) {
  using Channels = PerChannel<Deadzone<Scalar>, 2>;
  const std::array<Deadzone<Scalar>, 2> channels{Deadzone<Scalar>(current_deadzone),
                                                 Deadzone<Scalar>(Scalar(0))};
  return YawForceHW2016<Scalar>(yaw_force_2016<Scalar>(), Channels(channels));
}

}  // namespace endohaptics::model
