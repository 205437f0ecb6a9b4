//! @file
//! ForceEstimator: external force on each EndoWrist tool joint from motor current and velocity
//! (appendix C models, 5.2.3 friction gate, optional 4.4/6.2 Kalman correction) at the loop
//! period, through an explicit rate policy (decimation, or ZOH resampling of eqs. 4.1/4.2).
//! Inputs rad, rad/s, A; outputs roll N m, pitch and clamps N. See docs/models.md, ForceEstimator.
#pragma once

#include <Eigen/Core>
#include <Eigen/Eigenvalues>
#include <array>
#include <cmath>
#include <complex>
#include <concepts>
#include <cstddef>
#include <cstdint>
#include <limits>
#include <string>
#include <string_view>
#include <tuple>
#include <type_traits>
#include <unsupported/Eigen/MatrixFunctions>
#include <utility>

#include "endohaptics/core/error.hpp"
#include "endohaptics/estimation/steady_state_kalman.hpp"
#include "endohaptics/model/friction_model.hpp"
#include "endohaptics/model/hammerstein_wiener.hpp"
#include "endohaptics/model/presets_2016.hpp"
#include "endohaptics/model/state_space.hpp"
#include "endohaptics/model/static_nonlinearity.hpp"
#include "endohaptics/protocol/motor_order.hpp"
#include "endohaptics/protocol/packet_codec.hpp"

namespace endohaptics::estimation {

using protocol::Motor;

//! Outcome of `ForceEstimator::step`. On anything but `ok` the output and all internal state
//! (model states, decimation windows, friction gates) are left untouched.
enum class ForceStatus : std::uint8_t {
  ok = 0,             //!< forces written
  non_finite_input,   //!< NaN or +-Inf in position, velocity, current or setpoint
  non_finite_result,  //!< finite input, but a model produced NaN/Inf (diverging model, overflow)
};

//! Human-readable name of a status, for logs.
[[nodiscard]] constexpr std::string_view to_string(ForceStatus status) noexcept {
  switch (status) {
    case ForceStatus::ok:
      return "ok";
    case ForceStatus::non_finite_input:
      return "non-finite joint state";
    case ForceStatus::non_finite_result:
      return "non-finite force model result";
  }
  return "unknown status";
}

//! What the estimator reads each tick for the 4 EndoWrist motors, in motor order.
template <typename Scalar = double>
struct JointState {
  static_assert(std::is_floating_point_v<Scalar>, "JointState Scalar must be floating point");
  //! One value per motor, motor order.
  using Vector = Eigen::Matrix<Scalar, 4, 1>;
  Vector position = Vector::Zero();  //!< rad, motor side after gearing (sbRIO packet)
  Vector velocity = Vector::Zero();  //!< rad/s (sbRIO packet)
  Vector current = Vector::Zero();   //!< motor current, A (sbRIO packet "effort")
  Vector setpoint = Vector::Zero();  //!< rad, the position setpoint sent to the sbRIO
};

//! The estimator's input from a decoded sbRIO state packet and the setpoint packet we sent.
template <typename Scalar = double>
[[nodiscard]] JointState<Scalar> joint_state(const protocol::MotorState<4>& measured,
                                             const protocol::MotorSetpoint<4>& sent) noexcept {
  JointState<Scalar> state;
  state.position = measured.position.cast<Scalar>();
  state.velocity = measured.velocity.cast<Scalar>();
  state.current = measured.effort.cast<Scalar>();
  state.setpoint = sent.position.cast<Scalar>();
  return state;
}

//! The signals of one joint (one motor) for one tick.
template <typename Scalar = double>
struct JointSignals {
  Scalar position{};  //!< rad
  Scalar velocity{};  //!< rad/s
  Scalar current{};   //!< A
  Scalar setpoint{};  //!< rad
  //! Position error setpoint - position, rad (what the sbRIO's P controller acts on).
  [[nodiscard]] constexpr Scalar position_error() const noexcept { return setpoint - position; }
};

//! A per-joint force model as the estimator drives it: `force(s)` is the model's force output
//! at its current state (feedthrough from the signals `s`), `advance(s)` steps the model one
//! model period with `s` (all-or-nothing), `memoryless()` is true when the state never reaches
//! the output (the sample time then does not matter). Implementations: OpenLoop, KalmanCorrected.
template <typename M>
concept JointForceModel = requires(M& m, const M& cm,
                                   const JointSignals<typename M::ScalarType>& signals,
                                   const typename M::State& x) {
  typename M::ScalarType;
  typename M::State;
  requires std::is_floating_point_v<typename M::ScalarType>;
  { cm.sample_time() }
  noexcept->std::same_as<typename M::ScalarType>;
  { cm.memoryless() }
  noexcept->std::same_as<bool>;
  { cm.force(signals) }
  noexcept->std::same_as<typename M::ScalarType>;
  { m.advance(signals) }
  noexcept->std::same_as<model::StepStatus>;
  { cm.state() }
  noexcept->std::convertible_to<const typename M::State&>;
  { m.reset(x) }
  noexcept;
};

//! A JointForceModel that rate::Resample can convert: `M resampled(Scalar period) const`
//! (configuration time, may throw Error).
template <typename M>
concept ResamplableJointForceModel = JointForceModel<M> &&
    requires(const M& cm, typename M::ScalarType period) {
  { cm.resampled(period) } -> std::same_as<M>;
};

// ---------------------------------------------------------------------------------------------
// Discrete -> continuous -> discrete (configuration time).

namespace detail::force {

//! Tolerance for "ratio of sample times is an integer": 1e-9, or a few ulps of Scalar when that
//! is coarser (0.02f / 0.001f = 19.9999986).
template <typename Scalar>
double ratio_tolerance(double ratio) noexcept {
  return std::max(1e-9, 16.0 * static_cast<double>(std::numeric_limits<Scalar>::epsilon()) *
                            std::max(1.0, std::abs(ratio)));
}

//! Principal matrix logarithm (Eigen unsupported MatrixFunctions). Precondition: no eigenvalue
//! of `M` on the closed negative real axis.
template <typename Scalar>
Eigen::Matrix<Scalar, Eigen::Dynamic, Eigen::Dynamic> matrix_log(
    const Eigen::Matrix<Scalar, Eigen::Dynamic, Eigen::Dynamic>& M) {
  return M.log();
}

//! The linear block of a model: itself, or `linear()` of a Hammerstein-Wiener model.
template <typename M>
const auto& linear_block(const M& m) noexcept {
  if constexpr (requires { m.linear(); }) {
    return m.linear();
  } else {
    return m;
  }
}

}  // namespace detail::force

//! Continuous-time model whose ZOH discretisation at `discrete.sample_time()` is `discrete`
//! (scipy-style d2c 'zoh'): logm([[A, B], [0, I]]) / Ts = [[Ac, Bc], [0, 0]], Cc = C, Dc = D.
//! Throws Error if A is singular or has an eigenvalue on the closed negative real axis (no real
//! matrix logarithm: the message names the eigenvalue), or if the result is not finite.
template <int Nx, int Nu, int Ny, typename Scalar>
[[nodiscard]] model::ContinuousStateSpace<Nx, Nu, Ny, Scalar> to_continuous_zoh(
    const model::StateSpace<Nx, Nu, Ny, Scalar>& discrete) {
  const Scalar eps = std::numeric_limits<Scalar>::epsilon();
  // Dynamic size on purpose: configuration time only, and one instantiation of Eigen's
  // eigenvalue solver and matrix logarithm per Scalar instead of one per model size (they are
  // heavy to compile).
  using Dynamic = Eigen::Matrix<Scalar, Eigen::Dynamic, Eigen::Dynamic>;
  const Dynamic A = discrete.A();
  const Scalar norm = std::max(Scalar(1), A.norm());
  const Eigen::EigenSolver<Dynamic> solver(A, /*computeEigenvectors=*/false);
  if (solver.info() != Eigen::Success) {
    ENDOHAPTICS_THROW(Error("to_continuous_zoh: eigenvalues of A did not converge"));
  }
  for (Eigen::Index i = 0; i < solver.eigenvalues().size(); ++i) {
    const std::complex<Scalar> lambda = solver.eigenvalues()[i];
    if (std::abs(lambda) <= Scalar(100) * eps * norm) {
      ENDOHAPTICS_THROW(Error("to_continuous_zoh: A is singular (eigenvalue " +
                              endohaptics::detail::format_number(lambda) +
                              "), no matrix logarithm"));
    }
    if (lambda.real() < Scalar(0) && std::abs(lambda.imag()) <= std::sqrt(eps) * std::abs(lambda)) {
      ENDOHAPTICS_THROW(Error("to_continuous_zoh: A has the eigenvalue " +
                              endohaptics::detail::format_number(lambda) +
                              " on the negative real axis, no real matrix logarithm "
                              "(no continuous-time model has this discretisation)"));
    }
  }
  Dynamic M = Dynamic::Identity(Nx + Nu, Nx + Nu);
  M.topLeftCorner(Nx, Nx) = discrete.A();
  if constexpr (Nu > 0) M.topRightCorner(Nx, Nu) = discrete.B();
  const Dynamic L = detail::force::matrix_log(M) / discrete.sample_time();
  if (!L.allFinite()) {
    ENDOHAPTICS_THROW(Error("to_continuous_zoh: the matrix logarithm is not finite"));
  }
  typename model::ContinuousStateSpace<Nx, Nu, Ny, Scalar>::MatrixB Bc;
  if constexpr (Nu > 0) Bc = L.topRightCorner(Nx, Nu);
  return model::ContinuousStateSpace<Nx, Nu, Ny, Scalar>(L.topLeftCorner(Nx, Nx), Bc, discrete.C(),
                                                         discrete.D());
}

//! The same system sampled at `period` s instead (ZOH both ways), keeping the current state.
//! A memoryless model (C == 0: y = D u) only gets the new sample time; float models are
//! converted in double. Throws Error as `to_continuous_zoh` and `discretize_zoh` do.
template <int Nx, int Nu, int Ny, typename Scalar>
[[nodiscard]] model::StateSpace<Nx, Nu, Ny, Scalar> resample_zoh(
    const model::StateSpace<Nx, Nu, Ny, Scalar>& discrete, Scalar period) {
  model::detail::require_sample_time(period, "resample_zoh");
  if (discrete.C().isZero(Scalar(0))) {
    model::StateSpace<Nx, Nu, Ny, Scalar> same(discrete.A(), discrete.B(), discrete.C(),
                                               discrete.D(), period);
    same.reset(discrete.state());
    return same;
  }
  // float models are converted in double and rounded once at the end: the float matrix
  // logarithm of the nearly defective yaw model is off by several percent.
  using Wide = std::conditional_t<(sizeof(Scalar) < sizeof(double)), double, Scalar>;
  if constexpr (std::is_same_v<Wide, Scalar>) {
    auto resampled = model::discretize_zoh(to_continuous_zoh(discrete), period);
    resampled.reset(discrete.state());
    return resampled;
  } else {
    const model::StateSpace<Nx, Nu, Ny, Wide> wide(
        discrete.A().template cast<Wide>(), discrete.B().template cast<Wide>(),
        discrete.C().template cast<Wide>(), discrete.D().template cast<Wide>(),
        static_cast<Wide>(discrete.sample_time()));
    const auto fine = model::discretize_zoh(to_continuous_zoh(wide), static_cast<Wide>(period));
    model::StateSpace<Nx, Nu, Ny, Scalar> resampled(
        fine.A().template cast<Scalar>(), fine.B().template cast<Scalar>(),
        fine.C().template cast<Scalar>(), fine.D().template cast<Scalar>(), period);
    resampled.reset(discrete.state());
    return resampled;
  }
}

//! Hammerstein-Wiener model with its linear block resampled; the static nonlinearities are kept.
template <typename Linear, typename InputNL, typename OutputNL>
[[nodiscard]] model::HammersteinWiener<Linear, InputNL, OutputNL> resample_zoh(
    const model::HammersteinWiener<Linear, InputNL, OutputNL>& hw,
    typename Linear::ScalarType period) {
  return model::HammersteinWiener<Linear, InputNL, OutputNL>(
      resample_zoh(hw.linear(), period), hw.input_nonlinearity(), hw.output_nonlinearity());
}

// ---------------------------------------------------------------------------------------------
// Per-joint models.

//! A model the estimator can drive open loop: a model::StateSpace or model::HammersteinWiener
//! (anything with their interface and a `sample_time()`/`C()`, directly or via `linear()`) with
//! u = [current A] or u = [current A; velocity rad/s] and the force as output 0.
template <typename Model>
concept CurrentVelocityModel =
    model::LinearBlock<Model> &&(Model::inputs == 1 || Model::inputs == 2) && Model::outputs >= 1 &&
    requires(const Model& m) {
  { detail::force::linear_block(m).sample_time() } -> std::same_as<typename Model::ScalarType>;
  detail::force::linear_block(m).C();
};

//! No correction (the default): the model runs open loop on u = [current; velocity] (or
//! [current]) and its output 0 is the force, in the model's units and sign.
template <CurrentVelocityModel Model>
class OpenLoop {
 public:
  using ModelType = Model;                        //!< the wrapped model type
  using ScalarType = typename Model::ScalarType;  //!< floating-point type of the model
  using State = typename Model::State;            //!< model state x
  using Input = typename Model::Input;       //!< u = [current A] or [current A; velocity rad/s]
  using Signals = JointSignals<ScalarType>;  //!< one joint's signals for one tick

  //! Takes a copy of `model`, starting from its current state.
  explicit OpenLoop(Model model)
      : model_(std::move(model)),
        memoryless_(detail::force::linear_block(model_).C().isZero(ScalarType(0))) {}

  [[nodiscard]] const Model& model() const noexcept { return model_; }  //!< the wrapped model
  //! Sample time of the model, s.
  [[nodiscard]] ScalarType sample_time() const noexcept {
    return detail::force::linear_block(model_).sample_time();
  }
  //! True when C == 0: the output is D u only and the sample time does not matter.
  [[nodiscard]] bool memoryless() const noexcept { return memoryless_; }

  //! u = [current] or [current; velocity].
  [[nodiscard]] static Input input(const Signals& s) noexcept {
    Input u;
    u[0] = s.current;
    if constexpr (Model::inputs == 2) u[1] = s.velocity;
    return u;
  }
  //! Force (output 0) at the current state with feedthrough from `s`; does not advance.
  [[nodiscard]] ScalarType force(const Signals& s) const noexcept {
    return model_.output(input(s))[0];
  }
  //! One model period with input from `s`; all-or-nothing (model::StepStatus).
  [[nodiscard]] model::StepStatus advance(const Signals& s) noexcept {
    typename Model::Output y;
    return model_.update(input(s), y);
  }
  [[nodiscard]] const State& state() const noexcept { return model_.state(); }  //!< x(k)
  void reset(const State& x = State::Zero()) noexcept { model_.reset(x); }      //!< sets x(k)

  //! The model resampled at `period` s (`resample_zoh`). Throws Error as `resample_zoh` does.
  [[nodiscard]] OpenLoop resampled(ScalarType period) const requires
      requires(const Model& m, ScalarType t) {
    resample_zoh(m, t);
  }
  { return OpenLoop(resample_zoh(model_, period)); }

 private:
  Model model_;
  bool memoryless_;
};

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
  [[nodiscard]] model::StepStatus advance(const Signals& s) noexcept {
    const State saved = filter_.state();
    const Input u = input(s);
    if (filter_.update(measurement(s), u) != KalmanStatus::ok ||
        filter_.predict(u) != KalmanStatus::ok) {
      filter_.reset(saved);
      return model::StepStatus::non_finite_input;
    }
    if (!filter_.state().allFinite()) {
      filter_.reset(saved);
      return model::StepStatus::non_finite_result;
    }
    return model::StepStatus::ok;
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

// ---------------------------------------------------------------------------------------------
// Rate policies: how a model identified at Ts runs in a loop of period T.

namespace detail::force {

enum class RateMode : std::uint8_t { same, decimate, resample };

template <typename Scalar>
JointSignals<Scalar> operator+(const JointSignals<Scalar>& a, const JointSignals<Scalar>& b) {
  return {a.position + b.position, a.velocity + b.velocity, a.current + b.current,
          a.setpoint + b.setpoint};
}

//! Runs one joint model at the loop period according to the rate mode.
template <JointForceModel M, RateMode Mode>
requires(Mode != RateMode::resample || ResamplableJointForceModel<M>) class RateStepper {
 public:
  using Scalar = typename M::ScalarType;
  using Signals = JointSignals<Scalar>;
  //! Everything a tick may change.
  struct Snapshot {
    typename M::State state;
    Signals sum;
    int count;
  };

  //! Throws Error when the model cannot run at `loop_period` under this mode; `joint` names it.
  RateStepper(const M& model, Scalar loop_period, std::string_view joint)
      : model_(prepare(model, loop_period, joint)),
        ratio_(ticks_per_step(model, loop_period, joint)),
        memoryless_(model.memoryless()) {}

  [[nodiscard]] const M& model() const noexcept { return model_; }
  //! Loop ticks per model step (1 unless decimating).
  [[nodiscard]] int ratio() const noexcept { return ratio_; }

  //! Writes the force at the current state (feedthrough from `s`), then advances the model if a
  //! model period ends with this tick (decimation: with the mean of the window's signals).
  //! A memoryless model is never advanced (its state cannot reach the output). On anything but
  //! ok the caller restores a snapshot.
  [[nodiscard]] model::StepStatus tick(const Signals& s, Scalar& force) noexcept {
    force = model_.force(s);
    if (memoryless_) return model::StepStatus::ok;
    if constexpr (Mode == RateMode::decimate) {
      if (ratio_ > 1) {
        sum_ = sum_ + s;
        // Huge finite signals can overflow the window sum: refuse the tick, never keep an Inf.
        if (!std::isfinite(sum_.position) || !std::isfinite(sum_.velocity) ||
            !std::isfinite(sum_.current) || !std::isfinite(sum_.setpoint)) {
          return model::StepStatus::non_finite_result;
        }
        if (++count_ < ratio_) return model::StepStatus::ok;
        const Scalar inv = Scalar(1) / static_cast<Scalar>(ratio_);
        const Signals mean{sum_.position * inv, sum_.velocity * inv, sum_.current * inv,
                           sum_.setpoint * inv};
        sum_ = Signals{};
        count_ = 0;
        return model_.advance(mean);
      }
    }
    return model_.advance(s);
  }

  [[nodiscard]] Snapshot snapshot() const noexcept { return {model_.state(), sum_, count_}; }
  void restore(const Snapshot& saved) noexcept {
    model_.reset(saved.state);
    sum_ = saved.sum;
    count_ = saved.count;
  }
  //! Zero state, empty decimation window.
  void reset() noexcept { restore({M::State::Zero(), Signals{}, 0}); }

 private:
  static M prepare(const M& model, Scalar loop_period, std::string_view joint) {
    model::detail::require_sample_time(loop_period, "ForceEstimator loop period");
    (void)joint;
    if constexpr (Mode == RateMode::resample) {
      const double ratio = static_cast<double>(model.sample_time()) / loop_period;
      if (model.memoryless() || std::abs(ratio - 1.0) <= ratio_tolerance<Scalar>(ratio)) {
        return model;
      }
#if defined(__cpp_exceptions)
      try {
        return model.resampled(loop_period);
      } catch (const Error& error) {
        ENDOHAPTICS_THROW(Error("ForceEstimator (rate::Resample): the " + std::string(joint) +
                                " model cannot be resampled at " +
                                endohaptics::detail::format_number(loop_period) +
                                " s: " + error.what()));
      }
#else
      return model.resampled(loop_period);
#endif
    } else {
      return model;
    }
  }

  static int ticks_per_step(const M& model, Scalar loop_period, std::string_view joint) {
    if (model.memoryless() || Mode == RateMode::resample) return 1;
    const double ratio = static_cast<double>(model.sample_time()) / loop_period;
    const auto nearest = static_cast<long long>(std::llround(ratio));
    // At most a million ticks per model step (keeps the count an int).
    const bool integer =
        nearest >= 1 && nearest <= 1000000 &&
        std::abs(ratio - static_cast<double>(nearest)) <= ratio_tolerance<Scalar>(ratio);
    const std::string where = "ForceEstimator: the " + std::string(joint) +
                              " model's sample time " +
                              endohaptics::detail::format_number(model.sample_time()) + " s";
    if constexpr (Mode == RateMode::same) {
      if (!integer || nearest != 1) {
        ENDOHAPTICS_THROW(Error(where + " differs from the loop period " +
                                endohaptics::detail::format_number(loop_period) + " s (ratio " +
                                endohaptics::detail::format_number(ratio) +
                                "); choose a rate policy: rate::Decimate or rate::Resample"));
      }
    } else {
      if (!integer) {
        ENDOHAPTICS_THROW(Error(where + " is not an integer multiple of the loop period " +
                                endohaptics::detail::format_number(loop_period) + " s (ratio " +
                                endohaptics::detail::format_number(ratio) +
                                ", tolerance 1e-9); rate::Decimate needs one, use "
                                "rate::Resample or change the loop period"));
      }
    }
    return static_cast<int>(nearest);
  }

  M model_;
  int ratio_;
  bool memoryless_;
  Signals sum_{};
  int count_ = 0;
};

}  // namespace detail::force

//! Rate policies for ForceEstimator.
namespace rate {

//! No conversion: every dynamic model's sample time must equal the loop period (ratio 1 within
//! 1e-9), else the constructor throws Error. Memoryless models (y = D u) run at any period.
struct SameRate {
  //! Runs `M` at its own sample time, one step per loop tick.
  template <JointForceModel M>
  using Stepper = detail::force::RateStepper<M, detail::force::RateMode::same>;
};

//! Decimation: model Ts must be an integer multiple R of the loop period (within 1e-9, else
//! Error). The signals are averaged over R ticks and the model is stepped once per window; the
//! output between steps uses the held state (added latency: 0 to R - 1 ticks, see docs).
struct Decimate {
  //! Runs `M` once per R loop ticks on the window's mean signals.
  template <JointForceModel M>
  using Stepper = detail::force::RateStepper<M, detail::force::RateMode::decimate>;
};

//! Resampling: each model is converted to continuous time (matrix logarithm) and rediscretised
//! with ZOH at the loop period, then stepped every tick. Error if a model's A is singular or has
//! an eigenvalue on the closed negative real axis (the appendix C pitch model has -0.095).
struct Resample {
  //! Runs `M` resampled (ZOH) at the loop period, one step per tick.
  template <JointForceModel M>
  requires ResamplableJointForceModel<M>
  using Stepper = detail::force::RateStepper<M, detail::force::RateMode::resample>;
};

}  // namespace rate

//! `Rate` can run the joint model `M`: `Rate::Stepper<M>` exists and ticks without throwing.
template <typename Rate, typename M>
concept RatePolicyFor = JointForceModel<M> &&
    requires(typename Rate::template Stepper<M>& stepper,
             const JointSignals<typename M::ScalarType>& s, typename M::ScalarType& force) {
  { stepper.tick(s, force) }
  noexcept->std::same_as<model::StepStatus>;
  { stepper.snapshot() }
  noexcept;
  { stepper.reset() }
  noexcept;
  { stepper.ratio() }
  noexcept->std::same_as<int>;
};

// ---------------------------------------------------------------------------------------------
// The estimator.

//! The appendix C / 2016 per-joint models, wrapped for the estimator.
template <typename Scalar = double>
using RollModel2016 = OpenLoop<model::StateSpace<1, 1, 1, Scalar>>;  //!< static roll gain
template <typename Scalar = double>
using PitchModel2016 = OpenLoop<model::StateSpace<6, 2, 1, Scalar>>;  //!< linear pitch C.4-C.6
template <typename Scalar = double>
using ClampModel2016 = OpenLoop<model::YawForceHW2016<Scalar>>;  //!< yaw HW model C.1-C.3

//! One model per tool joint; both clamps use the same model type.
template <JointForceModel Roll, JointForceModel Pitch, JointForceModel Clamp>
struct ForceModels {
  Roll roll;     //!< roll torque model
  Pitch pitch;   //!< pitch force model
  Clamp clamp1;  //!< clamp 1 force model
  Clamp clamp2;  //!< clamp 2 force model
};

//! The 2016 defaults: roll static gain (0.070 N m/A), pitch linear preset, and the yaw
//! Hammerstein-Wiener preset for each clamp with the table 5.2 dead zone of its row (clamp 1:
//! "yaw" 0.21 A, clamp 2: "clamp" 0.20 A).
template <typename Scalar = double>
[[nodiscard]] ForceModels<RollModel2016<Scalar>, PitchModel2016<Scalar>, ClampModel2016<Scalar>>
models_2016() {
  return {RollModel2016<Scalar>(model::roll_torque_2016<Scalar>()),
          PitchModel2016<Scalar>(model::pitch_force_2016<Scalar>()),
          ClampModel2016<Scalar>(model::yaw_force_2016_hw<Scalar>(
              static_cast<Scalar>(model::yaw_static_friction_2016))),
          ClampModel2016<Scalar>(model::yaw_force_2016_hw<Scalar>(
              static_cast<Scalar>(model::clamp_static_friction_2016)))};
}

//! Everything but the models. Vectors are per tool joint (index = Motor: roll, pitch,
//! clamp1, clamp2). Defaults and their sources: docs/models.md, section ForceEstimator.
template <typename Scalar = double>
struct ForceEstimatorSettings {
  static_assert(std::is_floating_point_v<Scalar>, "ForceEstimatorSettings Scalar must be floating");
  using Vector = Eigen::Matrix<Scalar, 4, 1>;  //!< one value per tool joint (index = Motor)

  //! s, the period at which `step` is called (1 kHz loop).
  Scalar loop_period = Scalar(0.001);
  //! motor_order[m]: the tool joint of motor slot m in JointState (a permutation), as in
  //! CylindricalMapperConfig.
  std::array<Motor, 4> motor_order = {Motor::roll, Motor::pitch, Motor::clamp1, Motor::clamp2};
  //! +-1: +1 when positive motor current drives the joint towards positive setpoints. The 2016
  //! rig: -1 on every joint (the P controller's current opposes the position error in 40 of 41
  //! logs; identify_friction's current_sign is -1 on every free-movement log).
  Vector current_sign = Vector::Constant(Scalar(-1));
  //! > 0: model output unit -> N m (roll) or N; pitch model output is gram-force (9.80665e-3 N).
  Vector unit_scale = Vector(Scalar(1), Scalar(9.80665e-3), Scalar(1), Scalar(1));
  //! 5.2.3 gate levels per tool joint, table 5.2: roll 0.7 A, pitch 0.17 A, clamp1 0.21 A
  //! ("yaw" row), clamp2 0.20 A ("clamp" row); simplified model Kc = Ks, F_mu = 0.
  std::array<model::JointFriction<Scalar>, 4> friction = {
      model::JointFriction<Scalar>::simplified(Scalar(0.7)),
      model::JointFriction<Scalar>::simplified(Scalar(0.17)),
      model::JointFriction<Scalar>::simplified(Scalar(0.21)),
      model::JointFriction<Scalar>::simplified(Scalar(0.20))};
  //! Gate thresholds (standstill velocity, release fraction for the hysteresis).
  model::FrictionOptions<Scalar> friction_options{};
  //! >= 0, output units: |f| <= this gives 0, larger |f| is reduced by it. 0: off.
  Vector output_deadzone = Vector::Zero();
  //! > 0, output units: symmetric saturation. Roll 0.084 N m (1.2 A of figure E.8 x 0.070 N m/A);
  //! pitch and clamps 9.80665 N (the 1 kg load cell the models were identified with).
  Vector output_limit = Vector(Scalar(0.084), Scalar(9.80665), Scalar(9.80665), Scalar(9.80665));
};

//! Estimates the external force on each tool joint from the motor signals (worksheet ch. 4-5):
//! per joint, model y -> f = -current_sign x unit_scale x y (the external force along the
//! joint's positive setpoint, the convention of CylindricalMapper::map_force) -> friction gate
//! (5.2.3) -> dead zone -> saturation.
//! `Rate` is rate::Decimate (default: the only policy that runs the default 0.02 s models at the
//! default 1 ms loop period), rate::SameRate (refuses a model whose sample time differs from the
//! loop period) or rate::Resample (refuses the 2016 pitch model); the models are JointForceModel
//! policies (OpenLoop by default, KalmanCorrected for correction). `step` is noexcept and
//! allocation-free.
template <typename Rate = rate::Decimate, JointForceModel RollModel = RollModel2016<>,
          JointForceModel PitchModel = PitchModel2016<>,
          JointForceModel ClampModel = ClampModel2016<>>
requires RatePolicyFor<Rate, RollModel> && RatePolicyFor<Rate, PitchModel> &&
    RatePolicyFor<Rate, ClampModel>
class ForceEstimator {
 public:
  using ScalarType = typename RollModel::ScalarType;  //!< floating-point type of every model
  static_assert(std::is_same_v<ScalarType, typename PitchModel::ScalarType> &&
                    std::is_same_v<ScalarType, typename ClampModel::ScalarType>,
                "ForceEstimator: all joint models must use the same Scalar");
  static constexpr int joints = 4;                      //!< roll, pitch, clamp1, clamp2
  using Input = JointState<ScalarType>;                 //!< motor order
  using Forces = Eigen::Matrix<ScalarType, 4, 1>;       //!< tool-joint order (index = Motor)
  using Settings = ForceEstimatorSettings<ScalarType>;  //!< everything but the models
  using Models = ForceModels<RollModel, PitchModel, ClampModel>;  //!< one model per tool joint
  using Friction = model::FrictionModel<4, ScalarType>;           //!< the 5.2.3 friction gates
  using GateState = typename Friction::GateState;                 //!< per tool joint: gate open

  //! Validates everything; throws Error naming the field or joint and the offending value
  //! (rate mismatch, bad motor_order, current_sign not +-1, scale/limit not > 0, dead zone < 0,
  //! ...).
  ForceEstimator(const Models& models, const Settings& settings)
      : settings_(validated(settings)),
        // Braced: built (and checked) in joint order, so errors name the first bad joint.
        steppers_{Stepper<RollModel>(models.roll, settings.loop_period, "roll"),
                  Stepper<PitchModel>(models.pitch, settings.loop_period, "pitch"),
                  Stepper<ClampModel>(models.clamp1, settings.loop_period, "clamp1"),
                  Stepper<ClampModel>(models.clamp2, settings.loop_period, "clamp2")},
        friction_(settings.friction, settings.friction_options),
        deadzone_{model::Deadzone<ScalarType>(settings.output_deadzone[0]),
                  model::Deadzone<ScalarType>(settings.output_deadzone[1]),
                  model::Deadzone<ScalarType>(settings.output_deadzone[2]),
                  model::Deadzone<ScalarType>(settings.output_deadzone[3])},
        saturation_{model::Saturation<ScalarType>(settings.output_limit[0]),
                    model::Saturation<ScalarType>(settings.output_limit[1]),
                    model::Saturation<ScalarType>(settings.output_limit[2]),
                    model::Saturation<ScalarType>(settings.output_limit[3])},
        gain_(-settings.current_sign.cwiseProduct(settings.unit_scale)) {
    for (int m = 0; m < joints; ++m) {
      tool_joint_of_motor_[static_cast<std::size_t>(m)] =
          static_cast<int>(settings_.motor_order[static_cast<std::size_t>(m)]);
    }
  }

  //! The 2016 models (`models_2016`) with `settings`.
  explicit ForceEstimator(const Settings& settings = {}) requires
      std::same_as<Models, decltype(models_2016<ScalarType>())>
      : ForceEstimator(models_2016<ScalarType>(), settings) {}

  //! One loop tick. Writes the estimated external force per tool joint into `forces` (roll N m,
  //! pitch and clamps N; along each joint's positive setpoint) and returns ok; otherwise leaves
  //! `forces` and all internal state untouched. Precondition: called every `loop_period`.
  [[nodiscard]] ForceStatus step(const Input& input, Forces& forces) noexcept {
    if (!input.position.allFinite() || !input.velocity.allFinite() || !input.current.allFinite() ||
        !input.setpoint.allFinite()) {
      return ForceStatus::non_finite_input;
    }
    std::array<JointSignals<ScalarType>, 4> signals;
    Forces current;
    Forces velocity;
    for (int m = 0; m < joints; ++m) {
      const int j = tool_joint_of_motor_[static_cast<std::size_t>(m)];
      signals[static_cast<std::size_t>(j)] = {input.position[m], input.velocity[m],
                                              input.current[m], input.setpoint[m]};
      current[j] = input.current[m];
      velocity[j] = input.velocity[m];
    }

    const auto saved = snapshot();
    Forces raw;
    const bool ok = [&]<std::size_t... J>(std::index_sequence<J...>) {
      return ((std::get<J>(steppers_).tick(signals[J], raw[static_cast<int>(J)]) ==
               model::StepStatus::ok) &&
              ...);
    }
    (std::make_index_sequence<4>{});
    if (ok) raw = raw.cwiseProduct(gain_);
    if (!ok || !raw.allFinite()) {
      restore(saved);
      return ForceStatus::non_finite_result;
    }

    Forces gated;
    // Cannot fail: current, velocity and raw are finite.
    (void)friction_.update(current, velocity, raw, gated);
    raw_ = raw;
    for (int j = 0; j < joints; ++j) {
      const auto js = static_cast<std::size_t>(j);
      forces[j] = saturation_[js].apply(deadzone_[js].apply(gated[j]));
    }
    return ForceStatus::ok;
  }

  //! The interface of JointForceEstimator (TeleopLoop): one `step` on the decoded sbRIO
  //! state and the setpoint that was sent, `force` written in motor order (for map_force).
  //! Returns true and writes `force` only when the step is ok; `last_status()` says why not.
  bool estimate(const protocol::MotorState<4>& measured,
                const Eigen::Matrix<double, 4, 1>& setpoint,
                Eigen::Matrix<double, 4, 1>& force) noexcept {
    Input input;
    input.position = measured.position.template cast<ScalarType>();
    input.velocity = measured.velocity.template cast<ScalarType>();
    input.current = measured.effort.template cast<ScalarType>();
    input.setpoint = setpoint.template cast<ScalarType>();
    Forces tool;
    last_status_ = step(input, tool);
    if (last_status_ != ForceStatus::ok) return false;
    force = in_motor_order(tool).template cast<double>();
    return true;
  }
  //! Status of the last `estimate` call (ok before any).
  [[nodiscard]] ForceStatus last_status() const noexcept { return last_status_; }

  //! `forces` (tool-joint order, as `step` writes it) in motor order, e.g. for
  //! CylindricalMapper::map_force with the same motor_order.
  [[nodiscard]] Forces in_motor_order(const Forces& forces) const noexcept {
    Forces motor;
    for (int m = 0; m < joints; ++m)
      motor[m] = forces[tool_joint_of_motor_[static_cast<std::size_t>(m)]];
    return motor;
  }

  //! Zero model states, empty decimation windows, closed gates.
  void reset() noexcept {
    std::apply([](auto&... stepper) { (stepper.reset(), ...); }, steppers_);
    friction_.reset();
    raw_.setZero();
  }

  [[nodiscard]] const Settings& settings() const noexcept { return settings_; }  //!< as given
  //! Last model estimates as forces (-current_sign x unit_scale x y), before gate, dead zone and
  //! saturation.
  [[nodiscard]] const Forces& raw_estimate() const noexcept { return raw_; }
  //! Friction gate per tool joint: true while that joint's estimate is passed on.
  [[nodiscard]] const GateState& gate_open() const noexcept { return friction_.gate_open(); }
  //! Loop ticks per model step of a joint (rate::Decimate: Ts / loop period; otherwise 1).
  [[nodiscard]] int ticks_per_model_step(Motor joint) const noexcept {
    switch (joint) {
      case Motor::roll:
        return std::get<0>(steppers_).ratio();
      case Motor::pitch:
        return std::get<1>(steppers_).ratio();
      case Motor::clamp1:
        return std::get<2>(steppers_).ratio();
      case Motor::clamp2:
        return std::get<3>(steppers_).ratio();
    }
    return 0;
  }
  //! The model of tool joint `J` as it runs (e.g. resampled at the loop period).
  template <Motor J>
  [[nodiscard]] const auto& joint_model() const noexcept {
    return std::get<static_cast<std::size_t>(J)>(steppers_).model();
  }

 private:
  template <typename M>
  using Stepper = typename Rate::template Stepper<M>;
  using Steppers =
      std::tuple<Stepper<RollModel>, Stepper<PitchModel>, Stepper<ClampModel>, Stepper<ClampModel>>;
  using Snapshots =
      std::tuple<typename Stepper<RollModel>::Snapshot, typename Stepper<PitchModel>::Snapshot,
                 typename Stepper<ClampModel>::Snapshot, typename Stepper<ClampModel>::Snapshot>;

  Snapshots snapshot() const noexcept {
    return std::apply([](const auto&... stepper) { return Snapshots{stepper.snapshot()...}; },
                      steppers_);
  }
  void restore(const Snapshots& saved) noexcept {
    [&]<std::size_t... J>(std::index_sequence<J...>) {
      (std::get<J>(steppers_).restore(std::get<J>(saved)), ...);
    }
    (std::make_index_sequence<4>{});
  }

  static Settings validated(const Settings& s) {
    auto name = [](int j) { return std::string(protocol::to_string(static_cast<Motor>(j))); };
    std::array<bool, 4> seen{};
    for (std::size_t m = 0; m < s.motor_order.size(); ++m) {
      const auto j = static_cast<unsigned>(s.motor_order[m]);
      if (j >= 4u) {
        ENDOHAPTICS_THROW(Error("ForceEstimator: motor_order[" + std::to_string(m) +
                                "] is not a tool joint: " + std::to_string(j)));
      }
      if (seen[j]) {
        ENDOHAPTICS_THROW(
            Error("ForceEstimator: motor_order is not a permutation: " + name(static_cast<int>(j)) +
                  " appears twice (again at motor " + std::to_string(m) + ")"));
      }
      seen[j] = true;
    }
    for (int j = 0; j < 4; ++j) {
      if (s.current_sign[j] != ScalarType(1) && s.current_sign[j] != ScalarType(-1)) {
        ENDOHAPTICS_THROW(Error("ForceEstimator: current_sign[" + name(j) +
                                "] must be +1 or -1, got " +
                                endohaptics::detail::format_number(s.current_sign[j])));
      }
      if (!std::isfinite(s.unit_scale[j]) || !(s.unit_scale[j] > 0)) {
        ENDOHAPTICS_THROW(Error("ForceEstimator: unit_scale[" + name(j) +
                                "] must be finite and > 0, got " +
                                endohaptics::detail::format_number(s.unit_scale[j])));
      }
      if (!std::isfinite(s.output_deadzone[j]) || s.output_deadzone[j] < 0) {
        ENDOHAPTICS_THROW(Error("ForceEstimator: output_deadzone[" + name(j) +
                                "] must be finite and >= 0, got " +
                                endohaptics::detail::format_number(s.output_deadzone[j])));
      }
      if (!std::isfinite(s.output_limit[j]) || !(s.output_limit[j] > 0)) {
        ENDOHAPTICS_THROW(Error("ForceEstimator: output_limit[" + name(j) +
                                "] must be finite and > 0, got " +
                                endohaptics::detail::format_number(s.output_limit[j])));
      }
    }
    return s;
  }

  Settings settings_;
  Steppers steppers_;
  Friction friction_;
  std::array<model::Deadzone<ScalarType>, 4> deadzone_;
  std::array<model::Saturation<ScalarType>, 4> saturation_;
  Forces gain_;
  Forces raw_ = Forces::Zero();
  std::array<int, 4> tool_joint_of_motor_{};
  ForceStatus last_status_ = ForceStatus::ok;
};

//! The 2016 estimator (appendix C models, table 5.2 gates) with rate policy `Rate`.
template <typename Rate = rate::Decimate, typename Scalar = double>
using ForceEstimator2016 =
    ForceEstimator<Rate, RollModel2016<Scalar>, PitchModel2016<Scalar>, ClampModel2016<Scalar>>;

}  // namespace endohaptics::estimation
