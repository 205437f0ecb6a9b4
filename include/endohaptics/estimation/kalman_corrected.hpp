//! @file
//! KalmanCorrected: a JointForceModel corrected by a steady-state Kalman filter (worksheet 4.4,
//! 6.2): outputs y = [force; measured joint signals], the force read at the filtered estimate
//! x(k|k). Inputs current A, velocity rad/s; measured signals rad, rad/s or A.
#pragma once

#include <Eigen/Core>
#include <array>
#include <cstddef>
#include <cstdint>
#include <string>

#include "endohaptics/core/error.hpp"
#include "endohaptics/estimation/dare.hpp"
#include "endohaptics/estimation/joint_force_model.hpp"
#include "endohaptics/estimation/steady_state_kalman.hpp"
#include "endohaptics/model/state_space.hpp"

namespace endohaptics::estimation {

//! A joint signal a KalmanCorrected model output is compared with.
enum class Measured : std::uint8_t {
  position_error = 0,  //!< setpoint - position, rad
  velocity,            //!< rad/s
  position,            //!< rad
  current,             //!< A
};

//! Kalman correction (worksheet 4.4, 6.2): a steady-state Kalman filter (SteadyStateKalman) on a
//! model with u = [current] or [current; velocity] and outputs y = [force; m_1; ...; m_{Ny-1}],
//! where outputs 1.. predict measured joint signals (e.g. the position error). The force is
//! output 0 at the filtered estimate x(k|k); at the end of each model period the filter does its
//! measurement update with the period's signals, then its time update. The appendix C models have
//! only the force output and cannot be corrected.
template <int Nx, int Nu, int Ny, typename Scalar = double>
class KalmanCorrected {
  static_assert(Nu == 1 || Nu == 2, "KalmanCorrected: u = [current] or [current; velocity]");
  static_assert(Ny >= 2, "KalmanCorrected: output 0 is the force, outputs 1.. are measured");

 public:
  static constexpr int measurements = Ny - 1;           //!< measured outputs (all but the force)
  using ScalarType = Scalar;                            //!< floating-point type of the model
  using Model = model::StateSpace<Nx, Nu, Ny, Scalar>;  //!< outputs [force; measured signals]
  using Filter = SteadyStateKalman<Model, Ny - 1>;      //!< filter on outputs 1..Ny-1
  using State = typename Filter::State;                 //!< model state x
  using Input = typename Filter::Input;  //!< u = [current A] or [current A; velocity rad/s]
  using Signals = JointSignals<Scalar>;  //!< one joint's signals for one tick
  //! measured[i]: the joint signal that model output i + 1 predicts.
  using MeasuredSignals = std::array<Measured, static_cast<std::size_t>(Ny - 1)>;

  //! Output i + 1 of `model` predicts `measured[i]`. Q = cov of the process noise (Nx x Nx),
  //! R = cov of the measurement noise. Throws Error as SteadyStateKalman does, or on a
  //! `measured` value that is not a Measured enumerator.
  KalmanCorrected(const Model& model, const MeasuredSignals& measured,
                  const typename Filter::ProcessNoise& Q,
                  const typename Filter::MeasurementNoise& R,
                  const DareOptions<Scalar>& options = {})
      : filter_(model, model.C().template bottomRows<Ny - 1>(),
                model.D().template bottomRows<Ny - 1>(), Q, R, options),
        measured_(measured),
        C0_(model.C().row(0).transpose()),
        D0_(model.D().row(0).transpose()),
        sample_time_(model.sample_time()) {
    for (std::size_t i = 0; i < measured_.size(); ++i) {
      if (static_cast<unsigned>(measured_[i]) > static_cast<unsigned>(Measured::current)) {
        ENDOHAPTICS_THROW(Error(
            "KalmanCorrected: measured[" + std::to_string(i) +
            "] is not a Measured signal: " + std::to_string(static_cast<unsigned>(measured_[i]))));
      }
    }
  }

  [[nodiscard]] const Filter& filter() const noexcept { return filter_; }  //!< the Kalman filter
  //! Which joint signal each measured output predicts.
  [[nodiscard]] const MeasuredSignals& measured() const noexcept { return measured_; }
  //! Sample time of the model, s.
  [[nodiscard]] Scalar sample_time() const noexcept { return sample_time_; }
  [[nodiscard]] bool memoryless() const noexcept { return false; }  //!< always dynamic

  //! u = [current] or [current; velocity].
  [[nodiscard]] static Input input(const Signals& s) noexcept {
    Input u;
    u[0] = s.current;
    if constexpr (Nu == 2) u[1] = s.velocity;
    return u;
  }
  //! Measurement vector z picked from `s` as `measured()` says.
  [[nodiscard]] typename Filter::Measurement measurement(const Signals& s) const noexcept {
    typename Filter::Measurement z;
    for (int i = 0; i < Ny - 1; ++i) {
      switch (measured_[static_cast<std::size_t>(i)]) {
        case Measured::position_error:
          z[i] = s.position_error();
          break;
        case Measured::velocity:
          z[i] = s.velocity;
          break;
        case Measured::position:
          z[i] = s.position;
          break;
        case Measured::current:
          z[i] = s.current;
          break;
      }
    }
    return z;
  }
  //! Force (output 0) at the filtered estimate x(k|k) = x + M (z - Cm x - Dm u) with z and u
  //! from `s` (the measurement of this tick is used at once); does not advance.
  [[nodiscard]] Scalar force(const Signals& s) const noexcept {
    const Input u = input(s);
    typename Filter::Measurement innovation = measurement(s);
    innovation.noalias() -= filter_.estimate_measurement(u);
    State filtered = filter_.state();
    filtered.noalias() += filter_.gain() * innovation;
    Scalar y = C0_.dot(filtered);
    if constexpr (Nu > 0) y += D0_.dot(u);
    return y;
  }
  //! Measurement update with `s`, then time update; all-or-nothing.
  [[nodiscard]] model::NumericStatus advance(const Signals& s) noexcept {
    const State saved = filter_.state();
    const Input u = input(s);
    if (filter_.update(measurement(s), u) != NumericStatus::ok ||
        filter_.predict(u) != NumericStatus::ok) {
      filter_.reset(saved);
      return model::NumericStatus::non_finite_input;
    }
    if (!filter_.state().allFinite()) {
      filter_.reset(saved);
      return model::NumericStatus::non_finite_result;
    }
    return model::NumericStatus::ok;
  }
  [[nodiscard]] const State& state() const noexcept { return filter_.state(); }  //!< estimate
  void reset(const State& x = State::Zero()) noexcept { filter_.reset(x); }      //!< sets estimate

 private:
  Filter filter_;
  MeasuredSignals measured_;
  Eigen::Matrix<Scalar, Nx, 1> C0_;  // force row of C
  Eigen::Matrix<Scalar, Nu, 1> D0_;  // force row of D
  Scalar sample_time_;
};

}  // namespace endohaptics::estimation
