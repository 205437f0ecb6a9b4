//! @file
//! Clamp2016AsRun: the clamp force estimator the 2016 code ran (filipmrc/endohap,
//! src/Endowrist.cc and src/Kalman.cc), not the worksheet's appendix C: its own 6-state yaw model
//! (u = current, y = [velocity; force]) in a time-varying Kalman filter stepped twice per message,
//! fed position / dT as "velocity", the two force estimates averaged behind a sign gate and a
//! 0.1 dead zone. A JointForceModel; units as the 2016 code: A, rad, s, force in the model's (N).
//! Every difference from appendix C and every defect kept: docs/models.md, "The 2016 code as it
//! ran".
#pragma once

#include <Eigen/Core>
#include <Eigen/LU>
#include <cmath>

#include "endohaptics/core/error.hpp"
#include "endohaptics/core/parameter.hpp"
#include "endohaptics/estimation/joint_force_model.hpp"
#include "endohaptics/model/state_space.hpp"

namespace endohaptics::estimation {

//! T in Endowrist::Endowrist: the sample time the code assumed (it enters R only), s.
inline constexpr double as_run_2016_period = 0.02;
//! Q_yaw = 10*10 (Endowrist::initializeModels): process noise on the one input, A^2.
inline constexpr double as_run_2016_process_variance = 100.0;
//! R_yaw(0,0) = 10*10/T: noise of the "velocity" measurement.
inline constexpr double as_run_2016_velocity_variance = 100.0 / as_run_2016_period;
//! R_yaw(1,1) = (unsigned int)100000000*100000000/T: the product wraps in 32-bit unsigned
//! arithmetic to 1874919424 (not 1e16), so R(1,1) = 1874919424 / 0.02 = 9.37459712e10.
inline constexpr double as_run_2016_force_variance = 1874919424.0 / as_run_2016_period;
//! deadzone(value, 0.1) in Endowrist::forceEstimation (utils.h), in the force's unit.
inline constexpr double as_run_2016_deadzone = 0.1;

//! The yaw model of Endowrist::initializeModels (A_yaw, B_yaw, C_yaw as printed there):
//! 6 states, u = current A, y = [velocity; force], D = 0, Ts = T = 0.02 s. Not appendix C's.
template <typename Scalar = double>
[[nodiscard]] model::StateSpace<6, 1, 2, Scalar> yaw_model_2016_as_run() {
  using SS = model::StateSpace<6, 1, 2, Scalar>;
  const Eigen::Matrix<double, 6, 6> A{{0.9804, 0.0851, 0.1636, 0.1836, 0.0759, 0.1819},
                                      {-0.0119, 0.6809, -0.2967, 0.4604, -0.4634, 0.1466},
                                      {-0.0012, 0.2670, 0.9193, 0.0268, -0.2378, -0.1622},
                                      {-0.0020, -0.0913, 0.0933, 0.5568, 0.1060, -0.3030},
                                      {0.0008, 0.0198, -0.0275, 0.5082, 0.7115, -0.3731},
                                      {-0.0003, -0.0059, 0.0127, -0.1328, 0.3285, 0.4622}};
  const Eigen::Matrix<double, 6, 1> B{-0.2150, -1.2980, -1.5127, 2.0888, -1.2082, 1.7883};
  const Eigen::Matrix<double, 2, 6> C{{0.0594, -0.6962, 0.0325, 0.4309, -0.4352, 0.0929},
                                      {-0.3510, 0.0089, 0.2817, 0.3199, 0.2157, 0.5793}};
  return SS(A.cast<Scalar>(), B.cast<Scalar>(), C.cast<Scalar>(), SS::MatrixD::Zero(),
            static_cast<Scalar>(as_run_2016_period));
}

//! Settings of Clamp2016AsRun. Defaults: clamp motor 1 of Endowrist::forceEstimation.
template <typename Scalar = double>
struct Clamp2016AsRunParameters {
  //! +-1, the sign the code put on this clamp's current: -1 for clamp motor 1 (u1 = -eff[1]),
  //! +1 for clamp motor 4 (u1 = eff[2]).
  Scalar input_sign = Scalar(-1);
  //! dT, s: the time between messages that divides the position into the "velocity". The code
  //! took it from the wall clock; here it is fixed (default T, the 50 Hz the code assumed).
  Scalar message_period = static_cast<Scalar>(as_run_2016_period);
  //! >= 0, the output dead zone (0.1 in the code), force unit.
  Scalar deadzone = static_cast<Scalar>(as_run_2016_deadzone);

  //! Every field by name with its bound (core/parameter.hpp).
  template <typename Self, typename Visitor>
  static void for_each_field(Self& p, Visitor&& v) {
    v("input_sign", p.input_sign, Bound::unit_sign());
    v("message_period", p.message_period, sample_time_bound);
    v("deadzone", p.deadzone, Bound::in(0, max_joint_model_parameter));
  }
  //! Throws ParameterError naming the field, its value and the rule.
  void validate() const { for_each_field(*this, ParameterChecker{"Clamp2016AsRunParameters"}); }
};

//! The 2016 clamp estimator as it ran, for one clamp (see the file comment). Per message (one
//! advance, every T): Kalman::estimateOutput twice on the one filter, each with yv = [position /
//! dT; 0] and u = input_sign x current (the other clamp taken as this one's mirror image, see
//! docs/models.md); force = deadzone((ye1 + ye2) / 2, 0.1) when both force estimates have the
//! same strict sign, else 0. State: x (6) then P (6 x 6, column-major), 42 numbers.
//! noexcept and allocation-free per step; force() evaluates the two filter steps without keeping
//! them, advance() keeps them.
template <typename Scalar = double>
class Clamp2016AsRun {
 public:
  using ScalarType = Scalar;                            //!< floating-point type
  using Parameters = Clamp2016AsRunParameters<Scalar>;  //!< settings
  using Signals = JointSignals<Scalar>;                 //!< one joint's signals for one tick
  using State = Eigen::Matrix<Scalar, 42, 1>;           //!< x then P, column-major
  using Vector6 = Eigen::Matrix<Scalar, 6, 1>;          //!< filter state x
  using Matrix6 = Eigen::Matrix<Scalar, 6, 6>;          //!< covariance P
  using Output = Eigen::Matrix<Scalar, 2, 1>;           //!< [velocity; force] of the yaw model

  //! Throws ParameterError on a bad parameter.
  explicit Clamp2016AsRun(const Parameters& p = {}) : p_((p.validate(), p)) {
    const auto m = yaw_model_2016_as_run<Scalar>();
    A_ = m.A();
    B_ = m.B();
    C_ = m.C();
    R_ << static_cast<Scalar>(as_run_2016_velocity_variance), Scalar(0), Scalar(0),
        static_cast<Scalar>(as_run_2016_force_variance);
    BQBt_ = B_ * static_cast<Scalar>(as_run_2016_process_variance) * B_.transpose();
    reset();
  }

  [[nodiscard]] const Parameters& parameters() const noexcept { return p_; }  //!< as given
  //! T = 0.02 s: one advance per message.
  [[nodiscard]] Scalar sample_time() const noexcept {
    return static_cast<Scalar>(as_run_2016_period);
  }
  [[nodiscard]] bool memoryless() const noexcept { return false; }  //!< never

  //! The force the code would publish for this message `s`, at the current filter state (0 when
  //! an estimate is not finite: the sign gate).
  [[nodiscard]] Scalar force(const Signals& s) const noexcept {
    Vector6 x = x_of(z_);
    Matrix6 P = P_of(z_);
    Output ye1, ye2;
    message(s, x, P, ye1, ye2, false);
    // A NaN estimate fails both sign tests: the gate gives 0, as the 2016 code did.
    return combine(ye1[1], ye2[1]);
  }

  //! One message: both filter steps, kept. All or nothing: non_finite_input when the position
  //! or current is not finite (the velocity is not read), non_finite_result when the filter
  //! overflows.
  [[nodiscard]] model::NumericStatus advance(const Signals& s) noexcept {
    if (!std::isfinite(s.position) || !std::isfinite(s.current)) {
      return model::NumericStatus::non_finite_input;
    }
    Vector6 x = x_of(z_);
    Matrix6 P = P_of(z_);
    Output ye1, ye2;
    message(s, x, P, ye1, ye2);
    if (!x.allFinite() || !P.allFinite() || !ye1.allFinite() || !ye2.allFinite()) {
      return model::NumericStatus::non_finite_result;
    }
    z_.template head<6>() = x;
    Eigen::Map<Matrix6>(z_.data() + 6) = P;
    return model::NumericStatus::ok;
  }

  [[nodiscard]] const State& state() const noexcept { return z_; }  //!< x then P
  void reset(const State& z) noexcept { z_ = z; }                   //!< sets x and P
  //! Kalman::initializeFilter: x = 0, P = B Q B'.
  void reset() noexcept {
    z_.template head<6>().setZero();
    Eigen::Map<Matrix6>(z_.data() + 6) = BQBt_;
  }

  //! Kalman::estimateOutput once: measurement update with `yv`, output ye = C x, then the time
  //! update with `u`. `x` and `P` are updated in place.
  void filter_step(const Output& yv, Scalar u, Vector6& x, Matrix6& P, Output& ye) const noexcept {
    const Eigen::Matrix<Scalar, 6, 2> K = gain(P);
    x += K * (yv - C_ * x);
    P = (Matrix6::Identity() - K * C_) * P;
    ye = C_ * x;
    x = A_ * x + B_ * u;
    P = A_ * P * A_.transpose() + BQBt_;
  }

  //! The code's combination of the two force estimates: their mean behind the 0.1 dead zone when
  //! both are > 0 or both < 0, else 0 (utils.h deadzone: |v| < w gives 0, else v - sign(v) w).
  [[nodiscard]] Scalar combine(Scalar f1, Scalar f2) const noexcept {
    if (!((f1 > 0 && f2 > 0) || (f1 < 0 && f2 < 0))) return Scalar(0);
    const Scalar v = (f1 + f2) / Scalar(2);
    if (std::abs(v) < p_.deadzone) return Scalar(0);
    return v > 0 ? v - p_.deadzone : v + p_.deadzone;
  }

 private:
  static Vector6 x_of(const State& z) noexcept { return z.template head<6>(); }
  static Matrix6 P_of(const State& z) noexcept { return Eigen::Map<const Matrix6>(z.data() + 6); }
  // The gain of Kalman::estimateOutput: K = P C' (C P C' + R)^-1.
  [[nodiscard]] Eigen::Matrix<Scalar, 6, 2> gain(const Matrix6& P) const noexcept {
    const Eigen::Matrix<Scalar, 6, 2> PCt = P * C_.transpose();
    const Eigen::Matrix<Scalar, 2, 2> M = C_ * PCt + R_;
    return PCt * M.inverse();
  }
  // Endowrist::forceEstimation's two estimateOutput calls on one filter, for this clamp. With
  // `keep` false (force()), the second call stops at its output: its covariance and time updates
  // reach only the next message, which advance() computes.
  void message(const Signals& s, Vector6& x, Matrix6& P, Output& ye1, Output& ye2,
               bool keep = true) const noexcept {
    const Output yv(s.position / p_.message_period, Scalar(0));
    const Scalar u = p_.input_sign * s.current;
    filter_step(yv, u, x, P, ye1);
    if (keep) {
      filter_step(yv, u, x, P, ye2);
    } else {
      ye2 = C_ * (x + gain(P) * (yv - C_ * x));
    }
  }

  Parameters p_;
  Matrix6 A_;
  Vector6 B_;
  Eigen::Matrix<Scalar, 2, 6> C_;
  Eigen::Matrix<Scalar, 2, 2> R_;
  Matrix6 BQBt_;
  State z_;
};

static_assert(JointForceModel<Clamp2016AsRun<double>>);

}  // namespace endohaptics::estimation
