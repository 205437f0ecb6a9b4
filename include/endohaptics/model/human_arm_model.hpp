//! @file
//! Mass-spring-damper model of the operator's arm and hand (worksheet 5.1, figure 5.3,
//! eqs. 5.1-5.3, table 5.1), discretised by zero-order hold at the loop rate. Admittance: force
//! on the hand -> stylus position (eq. 5.3); impedance: imposed stylus motion -> force (eqs. 5.1,
//! 5.2). Per axis, plus a 3-axis convenience. Units: m, m/s, N, kg, s. See
//! docs/models/human_arm_model.md.
#pragma once

#include <Eigen/Core>
#include <array>
#include <cmath>
#include <cstdint>
#include <limits>
#include <string>
#include <string_view>
#include <type_traits>

#include "endohaptics/core/error.hpp"
#include "endohaptics/core/numeric_status.hpp"
#include "endohaptics/model/state_space.hpp"

namespace endohaptics::model {

//! Figure 5.3 constants; defaults are table 5.1 (from the worksheet's reference [33]).
template <typename Scalar = double>
struct HumanArmParameters {
  Scalar b1 = Scalar(4.5);    //!< hand damping, N s/m
  Scalar b2 = Scalar(7.9);    //!< arm damping, N s/m
  Scalar k1 = Scalar(48.8);   //!< hand stiffness, N/m
  Scalar k2 = Scalar(375.0);  //!< arm stiffness, N/m
  Scalar m_h = Scalar(1.46);  //!< arm mass, kg

  //! x_m / F_h at DC, (k1 + k2) / (k1 k2): the two springs in series, m/N.
  [[nodiscard]] constexpr Scalar static_compliance() const noexcept {
    return (k1 + k2) / (k1 * k2);
  }
  //! Member-wise equality.
  friend bool operator==(const HumanArmParameters&, const HumanArmParameters&) = default;
};

//! Throws Error unless every constant is finite and > 0; the message names field and value.
template <typename Scalar>
void validate(const HumanArmParameters<Scalar>& p) {
  const std::array<std::pair<std::string_view, Scalar>, 5> fields = {
      {{"b1", p.b1}, {"b2", p.b2}, {"k1", p.k1}, {"k2", p.k2}, {"m_h", p.m_h}}};
  for (const auto& [name, value] : fields) {
    if (!std::isfinite(value) || !(value > Scalar(0))) {
      ENDOHAPTICS_THROW(Error("HumanArmParameters: " + std::string(name) +
                              " must be finite and > 0, got " + detail::format_number(value)));
    }
  }
}

//! Continuous admittance (eq. 5.3): u = F_h [N], x = [x_m, x_h, v_h], y = [x_m, v_m] (m, m/s).
//! From eq. 5.1, v_m = v_h + (F_h - k1 (x_m - x_h)) / b1; from eq. 5.2,
//! m_h v_h' = F_h - k2 x_h - b2 v_h. Throws Error on invalid parameters.
template <typename Scalar>
[[nodiscard]] ContinuousStateSpace<3, 1, 2, Scalar> human_arm_admittance(
    const HumanArmParameters<Scalar>& p) {
  validate(p);
  using CSS = ContinuousStateSpace<3, 1, 2, Scalar>;
  typename CSS::MatrixA A;
  A << -p.k1 / p.b1, p.k1 / p.b1, Scalar(1),  //
      Scalar(0), Scalar(0), Scalar(1),        //
      Scalar(0), -p.k2 / p.m_h, -p.b2 / p.m_h;
  typename CSS::MatrixB B;
  B << Scalar(1) / p.b1, Scalar(0), Scalar(1) / p.m_h;
  typename CSS::MatrixC C;
  C << Scalar(1), Scalar(0), Scalar(0),  //
      -p.k1 / p.b1, p.k1 / p.b1, Scalar(1);
  typename CSS::MatrixD D;
  D << Scalar(0), Scalar(1) / p.b1;
  return CSS(A, B, C, D);
}

//! Continuous impedance (eqs. 5.1, 5.2): u = [x_m, v_m] (m, m/s), x = [x_h, v_h], y = F_h [N].
//! Its poles are the zeros of eq. 5.3. Throws Error on invalid parameters.
template <typename Scalar>
[[nodiscard]] ContinuousStateSpace<2, 2, 1, Scalar> human_arm_impedance(
    const HumanArmParameters<Scalar>& p) {
  validate(p);
  using CSS = ContinuousStateSpace<2, 2, 1, Scalar>;
  typename CSS::MatrixA A;
  A << Scalar(0), Scalar(1),  //
      -(p.k1 + p.k2) / p.m_h, -(p.b1 + p.b2) / p.m_h;
  typename CSS::MatrixB B;
  B << Scalar(0), Scalar(0),  //
      p.k1 / p.m_h, p.b1 / p.m_h;
  typename CSS::MatrixC C;
  C << -p.k1, -p.b1;
  typename CSS::MatrixD D;
  D << p.k1, p.b1;
  return CSS(A, B, C, D);
}

//! A tick returns `NumericStatus` (core/numeric_status.hpp); a non-finite force or motion is
//! replaced (force by 0 N, motion by the last valid position at rest) and the state stays finite.
using endohaptics::NumericStatus;

//! One axis of the figure 5.3 arm, discretised (zero-order hold) at the loop sample time. Both
//! causalities act on the same hand state (x_h, v_h), so a simulation may switch between them
//! from one tick to the next. F_h > 0 pushes the hand towards +x (the force the haptic device
//! renders on the hand); x_m is the stylus (hand contact) position.
template <typename Scalar = double>
class HumanArmModel {
  static_assert(std::is_floating_point_v<Scalar>, "HumanArmModel Scalar must be floating point");

 public:
  using Parameters = HumanArmParameters<Scalar>;   //!< figure 5.3 constants
  using Admittance = StateSpace<3, 1, 2, Scalar>;  //!< u = F_h; x = [x_m, x_h, v_h]; y = [x_m, v_m]
  using Impedance = StateSpace<2, 2, 1, Scalar>;   //!< u = [x_m, v_m]; x = [x_h, v_h]; y = F_h

  //! Discretises both models at `sample_time` (s). Throws Error on a sample time that is not
  //! finite and > 0 or on invalid parameters (the message names the value).
  explicit HumanArmModel(Scalar sample_time, const Parameters& parameters = {})
      : parameters_(checked(parameters, sample_time)),
        admittance_(discretize_zoh(human_arm_admittance(parameters_), sample_time)),
        impedance_(discretize_zoh(human_arm_impedance(parameters_), sample_time)) {}

  //! The validated constants.
  [[nodiscard]] const Parameters& parameters() const noexcept { return parameters_; }
  [[nodiscard]] Scalar sample_time() const noexcept { return admittance_.sample_time(); }  //!< s
  //! Discrete admittance (its state is current only while ticking `apply_force`).
  [[nodiscard]] const Admittance& admittance() const noexcept { return admittance_; }
  //! Discrete impedance (its state is current only while ticking `impose_motion`).
  [[nodiscard]] const Impedance& impedance() const noexcept { return impedance_; }

  //! Hand (arm mass) position x_h, m, at the current tick.
  [[nodiscard]] Scalar hand_position() const noexcept {
    return admittance_active_ ? admittance_.state()[1] : impedance_.state()[0];
  }
  //! Hand velocity v_h, m/s, at the current tick.
  [[nodiscard]] Scalar hand_velocity() const noexcept {
    return admittance_active_ ? admittance_.state()[2] : impedance_.state()[1];
  }

  //! Arm at rest at the origin (x_m = x_h = v_h = 0).
  void reset() noexcept {
    admittance_.reset();
    impedance_.reset();
    admittance_active_ = true;
    last_position_ = Scalar(0);
    last_velocity_ = Scalar(0);
  }

  //! Admittance tick: the device pushes the hand with `force` (N, held over the tick); writes the
  //! stylus `position` (m) and `velocity` (m/s) at this tick, then advances one sample.
  [[nodiscard]] NumericStatus apply_force(Scalar force, Scalar& position,
                                          Scalar& velocity) noexcept {
    NumericStatus status = NumericStatus::ok;
    if (!std::isfinite(force)) {
      force = Scalar(0);
      status = NumericStatus::non_finite_input;
    }
    if (!admittance_active_) {
      // Coming from impedance ticks: the stylus went on from the last imposed motion (held).
      typename Admittance::State x;
      x << last_position_ + last_velocity_ * sample_time(), impedance_.state();
      admittance_.reset(x);
      admittance_active_ = true;
    }
    typename Admittance::Input u;
    u << force;
    const typename Admittance::Output y = admittance_.step(u);
    position = y[0];
    velocity = y[1];
    return status;
  }

  //! Impedance tick: the device imposes the stylus `position` (m) and `velocity` (m/s), held
  //! over the tick; writes the force F_h (N) it exerts on the hand at this tick, then advances.
  [[nodiscard]] NumericStatus impose_motion(Scalar position, Scalar velocity,
                                            Scalar& force) noexcept {
    NumericStatus status = NumericStatus::ok;
    if (!std::isfinite(position) || !std::isfinite(velocity)) {
      position = admittance_active_ ? admittance_.state()[0] : last_position_;
      velocity = Scalar(0);
      status = NumericStatus::non_finite_input;
    }
    if (admittance_active_) {
      impedance_.reset(admittance_.state().template tail<2>());
      admittance_active_ = false;
    }
    typename Impedance::Input u;
    u << position, velocity;
    force = impedance_.step(u)[0];
    last_position_ = position;
    last_velocity_ = velocity;
    return status;
  }

 private:
  static const Parameters& checked(const Parameters& p, Scalar sample_time) {
    if (!std::isfinite(sample_time) || !(sample_time > Scalar(0))) {
      ENDOHAPTICS_THROW(Error("HumanArmModel: sample time must be finite and > 0 s, got " +
                              detail::format_number(sample_time)));
    }
    validate(p);
    return p;
  }

  Parameters parameters_;
  Admittance admittance_;
  Impedance impedance_;
  bool admittance_active_ = true;
  Scalar last_position_ = Scalar(0);
  Scalar last_velocity_ = Scalar(0);
};

//! Three independent axes (x, y, z of the stylus), each a HumanArmModel; per-axis parameters.
template <typename Scalar = double>
class HumanArm3 {
 public:
  using Axis = HumanArmModel<Scalar>;             //!< the model of one axis
  using Parameters = HumanArmParameters<Scalar>;  //!< figure 5.3 constants of one axis
  using Vector = Eigen::Matrix<Scalar, 3, 1>;     //!< one value per axis (x, y, z)

  //! Same parameters on every axis. Throws Error like HumanArmModel.
  explicit HumanArm3(Scalar sample_time, const Parameters& parameters = {})
      : HumanArm3(sample_time, {parameters, parameters, parameters}) {}
  //! Parameters per axis (x, y, z). Throws Error like HumanArmModel.
  HumanArm3(Scalar sample_time, const std::array<Parameters, 3>& parameters)
      : axes_{Axis(sample_time, parameters[0]), Axis(sample_time, parameters[1]),
              Axis(sample_time, parameters[2])} {}

  //! Axis `i` (0 = x, 1 = y, 2 = z). Precondition: 0 <= i < 3.
  [[nodiscard]] const Axis& axis(int i) const noexcept {
    ENDOHAPTICS_ASSERT(i >= 0 && i < 3);
    return axes_[static_cast<std::size_t>(i)];
  }
  void reset() noexcept {  //!< every axis at rest at the origin
    for (Axis& a : axes_) a.reset();
  }

  //! Admittance tick on every axis: force (N) in, stylus position (m) and velocity (m/s) out.
  //! Returns `non_finite_input` if any axis replaced a non-finite force.
  [[nodiscard]] NumericStatus apply_force(const Vector& force, Vector& position,
                                          Vector& velocity) noexcept {
    NumericStatus status = NumericStatus::ok;
    for (int i = 0; i < 3; ++i) {
      if (axes_[static_cast<std::size_t>(i)].apply_force(force[i], position[i], velocity[i]) !=
          NumericStatus::ok) {
        status = NumericStatus::non_finite_input;
      }
    }
    return status;
  }

  //! Impedance tick on every axis: stylus position (m) and velocity (m/s) in, force (N) out.
  [[nodiscard]] NumericStatus impose_motion(const Vector& position, const Vector& velocity,
                                            Vector& force) noexcept {
    NumericStatus status = NumericStatus::ok;
    for (int i = 0; i < 3; ++i) {
      if (axes_[static_cast<std::size_t>(i)].impose_motion(position[i], velocity[i], force[i]) !=
          NumericStatus::ok) {
        status = NumericStatus::non_finite_input;
      }
    }
    return status;
  }

 private:
  std::array<Axis, 3> axes_;
};

}  // namespace endohaptics::model
