//! @file
//! ForceEstimator: external force on each EndoWrist tool joint from motor current and velocity
//! (appendix C models, 5.2.3 friction gate, optional 4.4/6.2 Kalman correction) at the loop
//! period, through an explicit rate policy (decimation, or ZOH resampling of eqs. 4.1/4.2).
//! Inputs rad, rad/s, A; outputs roll N m, pitch and clamps N. See docs/models.md, ForceEstimator.
#pragma once

#include <Eigen/Core>
#include <array>
#include <cmath>
#include <concepts>
#include <cstddef>
#include <cstdint>
#include <limits>
#include <string>
#include <string_view>
#include <tuple>
#include <type_traits>
#include <utility>

#include "endohaptics/core/error.hpp"
#include "endohaptics/core/numeric_status.hpp"
#include "endohaptics/core/parameter.hpp"
#include "endohaptics/estimation/force_models_2016.hpp"
#include "endohaptics/estimation/joint_force_model.hpp"
#include "endohaptics/estimation/kalman_corrected.hpp"
#include "endohaptics/estimation/open_loop.hpp"
#include "endohaptics/estimation/rate_policy.hpp"
#include "endohaptics/estimation/stiction_hold.hpp"
#include "endohaptics/estimation/zoh_resampling.hpp"
#include "endohaptics/model/friction_model.hpp"
#include "endohaptics/model/state_space.hpp"
#include "endohaptics/model/static_nonlinearity.hpp"
#include "endohaptics/protocol/motor_order.hpp"
#include "endohaptics/protocol/packet_codec.hpp"

namespace endohaptics::estimation {

using protocol::Motor;

//! `ForceEstimator::step` returns `NumericStatus` (core/numeric_status.hpp); on anything but `ok`
//! the output and all internal state (model states, decimation windows, friction gates) are left
//! untouched.
using endohaptics::NumericStatus;

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
  state.current = measured.current.cast<Scalar>();
  state.setpoint = sent.position.cast<Scalar>();
  return state;
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
  //! logs; identification::identify_friction's current_sign is -1 on every free-movement log).
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
  //! >= 0, rad of motor (gear-output) travel: the stiction memory. A cable-driven joint pressed
  //! into an object stays where it is while its motor backs off, until the tendon's torque has
  //! fallen through the static-friction band, 2 tau_s / k_t of travel: its contact force does not
  //! change, but the motor current relaxes and a model of current and velocity reads less, down
  //! to 0. So once the estimate falls on the same side while the motor backs off, the estimate it
  //! had is held until the motor has backed off more than the stuck travel from where it last
  //! pressed (then the joint slides out and the estimate is followed again). 0: off (the estimate
  //! is passed on as it is).
  Vector stick_travel = Vector::Zero();
  //! >= 0, rad: the play the stuck travel adds while the held force is below `stick_force`: a
  //! contact whose torque is below the static friction cannot push the joint out, so the tendon
  //! must go slack through the play and pull it out from the other side.
  Vector stick_play = Vector::Zero();
  //! >= 0, output units (N): tau_s / lever, the force below which `stick_play` is added.
  Vector stick_force = Vector::Zero();
  //! >= 0, output units (N): a held force beyond this is also held while the estimate falls
  //! *through zero* (StictionHold's contact level: the estimate's error bound in free motion);
  //! +infinity, the default: held on the same side only. Not a configuration key (a file holds
  //! no infinity); the passivity sweep sets it (sim::ClosedLoopConfig::stiction_through_zero).
  Vector stick_contact_level = Vector::Constant(std::numeric_limits<Scalar>::infinity());

  //! The per-joint settings by their configuration names, with their bounds (core/parameter.hpp;
  //! the friction by its static levels): the one list ForceEstimator's validation and the bridge
  //! configuration use. loop_period, motor_order and friction_options are checked apart.
  template <typename Self, typename Visitor>
  static void for_each_field(Self& p, Visitor&& v) {
    constexpr double inf = std::numeric_limits<double>::infinity();
    v("current_sign", p.current_sign, Bound::unit_sign());
    v("unit_scale", p.unit_scale, Bound::above(0, inf));
    v("friction_level", model::StaticFrictionLevels(p.friction), Bound::in(0, inf, "A"));
    v("output_deadzone", p.output_deadzone, Bound::in(0, inf));
    v("output_limit", p.output_limit, Bound::above(0, inf));
    v("stick_travel", p.stick_travel, Bound::in(0, inf, "rad"));
    v("stick_play", p.stick_play, Bound::in(0, inf, "rad"));
    v("stick_force", p.stick_force, Bound::in(0, inf));
  }
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
        gain_(-settings.current_sign.cwiseProduct(settings.unit_scale)),
        stick_(settings_, settings_.stick_contact_level.template cast<ScalarType>()) {
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
  [[nodiscard]] NumericStatus step(const Input& input, Forces& forces) noexcept {
    if (!input.position.allFinite() || !input.velocity.allFinite() || !input.current.allFinite() ||
        !input.setpoint.allFinite()) {
      return NumericStatus::non_finite_input;
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
               model::NumericStatus::ok) &&
              ...);
    }
    (std::make_index_sequence<4>{});
    if (ok) raw = raw.cwiseProduct(gain_);
    if (!ok || !raw.allFinite()) {
      restore(saved);
      return NumericStatus::non_finite_result;
    }

    Forces gated;
    // Cannot fail: current, velocity and raw are finite.
    (void)friction_.update(current, velocity, raw, gated);
    raw_ = raw;
    for (int j = 0; j < joints; ++j) {
      const auto js = static_cast<std::size_t>(j);
      const ScalarType held = stick_.apply(j, gated[j], signals[js].position);
      forces[j] = saturation_[js].apply(deadzone_[js].apply(held));
    }
    return NumericStatus::ok;
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
    input.current = measured.current.template cast<ScalarType>();
    input.setpoint = setpoint.template cast<ScalarType>();
    Forces tool;
    last_status_ = step(input, tool);
    if (last_status_ != NumericStatus::ok) return false;
    force = in_motor_order(tool).template cast<double>();
    return true;
  }
  //! Status of the last `estimate` call (ok before any).
  [[nodiscard]] NumericStatus last_status() const noexcept { return last_status_; }

  //! `forces` (tool-joint order, as `step` writes it) in motor order, e.g. for
  //! CylindricalMapper::map_force with the same motor_order.
  [[nodiscard]] Forces in_motor_order(const Forces& forces) const noexcept {
    Forces motor;
    for (int m = 0; m < joints; ++m)
      motor[m] = forces[tool_joint_of_motor_[static_cast<std::size_t>(m)]];
    return motor;
  }

  //! Zero model states, empty decimation windows, closed gates, nothing held.
  void reset() noexcept {
    std::apply([](auto&... stepper) { (stepper.reset(), ...); }, steppers_);
    friction_.reset();
    raw_.setZero();
    stick_.reset();
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
    Settings::for_each_field(s, ParameterChecker{"ForceEstimator"});
    return s;
  }

  Settings settings_;
  Steppers steppers_;
  Friction friction_;
  std::array<model::Deadzone<ScalarType>, 4> deadzone_;
  std::array<model::Saturation<ScalarType>, 4> saturation_;
  Forces gain_;
  Forces raw_ = Forces::Zero();
  StictionHold<ScalarType> stick_;  // Settings::stick_*
  std::array<int, 4> tool_joint_of_motor_{};
  NumericStatus last_status_ = NumericStatus::ok;
};

//! The 2016 estimator (appendix C models, table 5.2 gates) with rate policy `Rate`.
template <typename Rate = rate::Decimate, typename Scalar = double>
using ForceEstimator2016 =
    ForceEstimator<Rate, RollModel2016<Scalar>, PitchModel2016<Scalar>, ClampModel2016<Scalar>>;

}  // namespace endohaptics::estimation
