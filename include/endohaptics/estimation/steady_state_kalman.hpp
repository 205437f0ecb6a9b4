//! @file
//! Steady-state Kalman filter (worksheet 4.4.1, 6.2) correcting the states of a discrete model
//! x+ = A x + B u + w, z = Cm x + Dm u + v (cov w = Q, cov v = R) from measurements z, and
//! estimating all model outputs y = C x + D u (e.g. the unmeasured force). Filter form, constant
//! gain M = P Cm' (Cm P Cm' + R)^-1 from the DARE of dare.hpp. Units: those of the model.
#pragma once

#include <Eigen/Core>
#include <concepts>
#include <cstdint>
#include <string_view>
#include <type_traits>

#include "endohaptics/core/error.hpp"
#include "endohaptics/core/numeric_status.hpp"
#include "endohaptics/estimation/dare.hpp"

namespace endohaptics::estimation {

//! `predict` and `update` return `NumericStatus` (core/numeric_status.hpp); on anything but `ok`
//! the estimate is left untouched.
using endohaptics::NumericStatus;

namespace detail {
template <typename Model, int Rows, int Cols>
using ModelMatrix = Eigen::Matrix<typename Model::ScalarType, Rows, Cols>;
}  // namespace detail

//! A discrete LTI model as model::StateSpace describes one: sizes `states`, `inputs`, `outputs`,
//! `ScalarType`, and fixed-size matrices A(), B(), C(), D() of x+ = A x + B u, y = C x + D u.
template <typename Model>
concept DiscreteLinearModel = requires(const Model& m) {
  typename Model::ScalarType;
  requires std::is_floating_point_v<typename Model::ScalarType>;
  requires Model::states >= 1 && Model::inputs >= 0 && Model::outputs >= 1;
  // clang-format off
  { m.A() } -> std::convertible_to<detail::ModelMatrix<Model, Model::states, Model::states>>;
  { m.B() } -> std::convertible_to<detail::ModelMatrix<Model, Model::states, Model::inputs>>;
  { m.C() } -> std::convertible_to<detail::ModelMatrix<Model, Model::outputs, Model::states>>;
  { m.D() } -> std::convertible_to<detail::ModelMatrix<Model, Model::outputs, Model::inputs>>;
  // clang-format on
};

//! Steady-state Kalman filter for `Model` with `Nm` measurements (default: every model output is
//! measured). Per tick: `update(z, u)` (measurement correction), read `state()` or
//! `estimate_output(u)`, then `predict(u)` (time update). All tick functions are noexcept and
//! allocation-free.
template <DiscreteLinearModel Model, int Nm = Model::outputs>
class SteadyStateKalman {
  static_assert(Nm >= 1, "SteadyStateKalman needs at least one measurement (Nm >= 1)");

 public:
  using ScalarType = typename Model::ScalarType;  //!< scalar type of the model
  static constexpr int states = Model::states;    //!< state dimension
  static constexpr int inputs = Model::inputs;    //!< input dimension
  static constexpr int outputs = Model::outputs;  //!< model output dimension
  static constexpr int measurements = Nm;         //!< measurement dimension

  using State = Eigen::Matrix<ScalarType, states, 1>;              //!< state vector x
  using Input = Eigen::Matrix<ScalarType, inputs, 1>;              //!< input vector u
  using Output = Eigen::Matrix<ScalarType, outputs, 1>;            //!< output vector y = C x + D u
  using Measurement = Eigen::Matrix<ScalarType, Nm, 1>;            //!< z = Cm x + Dm u + v
  using MatrixA = Eigen::Matrix<ScalarType, states, states>;       //!< state matrix A
  using MatrixB = Eigen::Matrix<ScalarType, states, inputs>;       //!< input matrix B
  using MatrixC = Eigen::Matrix<ScalarType, outputs, states>;      //!< output matrix C
  using MatrixD = Eigen::Matrix<ScalarType, outputs, inputs>;      //!< feedthrough matrix D
  using MeasurementC = Eigen::Matrix<ScalarType, Nm, states>;      //!< Cm
  using MeasurementD = Eigen::Matrix<ScalarType, Nm, inputs>;      //!< Dm
  using Covariance = Eigen::Matrix<ScalarType, states, states>;    //!< state error covariance (P)
  using ProcessNoise = Eigen::Matrix<ScalarType, states, states>;  //!< Q = cov(w)
  using MeasurementNoise = Eigen::Matrix<ScalarType, Nm, Nm>;      //!< R = cov(v)
  using Gain = Eigen::Matrix<ScalarType, states, Nm>;              //!< Kalman gain M

  //! Every model output is measured: Cm = C, Dm = D. Throws Error as `solve_filter_dare` does
  //! (bad Q or R, (A, C) not detectable, no convergence) or on a non-finite B or D.
  //! (A template, so that an explicit instantiation of the class does not instantiate it for
  //! an Nm it does not apply to: clang 14 would.)
  template <int Measured = Nm>
  requires(Measured == Model::outputs)
      SteadyStateKalman(const Model& model, const ProcessNoise& Q, const MeasurementNoise& R,
                        const DareOptions<ScalarType>& options = {})
      : SteadyStateKalman(model, model.C(), model.D(), Q, R, options) {}

  //! Measurements z = Cm x + Dm u + v separate from the model outputs y = C x + D u (e.g. the
  //! position error and velocity measured, the force only estimated). Throws Error as
  //! `solve_filter_dare` does for (A, Cm, Q, R), or on a non-finite B, C, D or Dm.
  SteadyStateKalman(const Model& model, const MeasurementC& C_meas, const MeasurementD& D_meas,
                    const ProcessNoise& Q, const MeasurementNoise& R,
                    const DareOptions<ScalarType>& options = {})
      : A_(model.A()),
        B_(model.B()),
        C_(model.C()),
        D_(model.D()),
        C_meas_(C_meas),
        D_meas_(D_meas),
        riccati_(solve_filter_dare(A_, C_meas_, Q, R, options)) {
    constexpr std::string_view owner = "SteadyStateKalman";
    detail::require_finite(B_, owner, "B");
    detail::require_finite(C_, owner, "C");
    detail::require_finite(D_, owner, "D");
    detail::require_finite(D_meas_, owner, "D_meas");
    // M = P Cm' S^-1 with S = Cm P Cm' + R symmetric PD, so M' = S^-1 Cm P. Dynamic sizes in
    // double (as in dare.hpp): the Cholesky factorisation is compiled once (configuration time).
    using Work = detail::WorkScalar<ScalarType>;
    using Dynamic = detail::DynamicMatrix<Work>;
    const Dynamic P = riccati_.P.template cast<Work>();
    const Dynamic Cm = C_meas_.template cast<Work>();
    const Dynamic R_work = R.template cast<Work>();
    const Dynamic S = Cm * P * Cm.transpose() + (R_work + R_work.transpose()) / Work(2);
    const Dynamic M_transposed = S.llt().solve(Cm * P);
    gain_ = M_transposed.transpose().template cast<ScalarType>();
    const Dynamic filtered = P - M_transposed.transpose() * S * M_transposed;
    filtered_covariance_ =
        ((filtered + filtered.transpose()) / Work(2)).template cast<ScalarType>();
  }

  //! Time update x <- A x + B u. Returns non_finite_input (estimate unchanged) on NaN/Inf in u.
  [[nodiscard]] NumericStatus predict(const Input& u) noexcept {
    if constexpr (inputs > 0) {
      if (!u.allFinite()) return NumericStatus::non_finite_input;
      State next = A_ * x_;
      next.noalias() += B_ * u;
      x_ = next;
    } else {
      x_ = (A_ * x_).eval();
    }
    return NumericStatus::ok;
  }

  //! Measurement update x <- x + M (z - Cm x - Dm u), u the input of this sample. Returns
  //! non_finite_measurement or non_finite_input (estimate unchanged) on NaN/Inf.
  [[nodiscard]] NumericStatus update(const Measurement& z, const Input& u) noexcept {
    if (!z.allFinite()) return NumericStatus::non_finite_measurement;
    Measurement innovation = z;
    innovation.noalias() -= C_meas_ * x_;
    if constexpr (inputs > 0) {
      if (!u.allFinite()) return NumericStatus::non_finite_input;
      innovation.noalias() -= D_meas_ * u;
    }
    x_.noalias() += gain_ * innovation;
    return NumericStatus::ok;
  }

  //! Current estimate: x(k|k) after `update`, x(k+1|k) after `predict`.
  [[nodiscard]] const State& state() const noexcept { return x_; }

  //! Sets the estimate to `x0` (zero by default).
  void reset(const State& x0 = State::Zero()) noexcept { x_ = x0; }

  //! Model outputs y = C x + D u at the current estimate, including unmeasured ones.
  [[nodiscard]] Output estimate_output(const Input& u) const noexcept {
    Output y = C_ * x_;
    if constexpr (inputs > 0) y.noalias() += D_ * u;
    return y;
  }

  //! Expected measurement Cm x + Dm u at the current estimate.
  [[nodiscard]] Measurement estimate_measurement(const Input& u) const noexcept {
    Measurement z = C_meas_ * x_;
    if constexpr (inputs > 0) z.noalias() += D_meas_ * u;
    return z;
  }

  //! Filter gain M = P Cm' (Cm P Cm' + R)^-1, used by `update`.
  [[nodiscard]] const Gain& gain() const noexcept { return gain_; }
  //! Predictor gain L = A M of the one-step form x(k+1|k) = A x(k|k-1) + B u + L (z - Cm x - Dm u).
  [[nodiscard]] Gain predictor_gain() const noexcept { return A_ * gain_; }
  //! P: steady-state error covariance of x(k+1|k), i.e. of `state()` after `predict`.
  [[nodiscard]] const Covariance& predicted_covariance() const noexcept { return riccati_.P; }
  //! P - M Cm P: steady-state error covariance of x(k|k), i.e. of `state()` after `update`.
  [[nodiscard]] const Covariance& filtered_covariance() const noexcept {
    return filtered_covariance_;
  }
  //! The DARE solution with its iteration count and residual.
  [[nodiscard]] const DareSolution<states, ScalarType>& riccati() const noexcept {
    return riccati_;
  }
  [[nodiscard]] const MeasurementC& measurement_C() const noexcept { return C_meas_; }  //!< Cm
  [[nodiscard]] const MeasurementD& measurement_D() const noexcept { return D_meas_; }  //!< Dm

 private:
  MatrixA A_;
  MatrixB B_;
  MatrixC C_;
  MatrixD D_;
  MeasurementC C_meas_;
  MeasurementD D_meas_;
  DareSolution<states, ScalarType> riccati_;
  Gain gain_;
  Covariance filtered_covariance_;
  State x_ = State::Zero();
};

}  // namespace endohaptics::estimation
