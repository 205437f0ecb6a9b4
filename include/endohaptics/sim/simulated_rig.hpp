//! @file
//! SimulatedRig: the 2016 EndoWrist test rig (worksheet 2.x, 5.2, 5.4, app. E) as a multi-rate
//! simulation: DC motor + gearhead + tendon with play and stick-slip friction, the table 5.3
//! cascade (P position 2 kHz -> PI speed 5.36 kHz -> PI current 53.6 kHz), x4 encoder counting
//! and contact environments. Units: rad and rad/s on the gear output ("motor side after
//! gearing"), A, V, N m, N at the tool. Equations and sources: docs/models/sim.md.
#pragma once

#include <Eigen/Core>
#include <algorithm>
#include <array>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <limits>
#include <numbers>
#include <string>
#include <string_view>
#include <type_traits>

#include "endohaptics/core/error.hpp"
#include "endohaptics/protocol/packet_codec.hpp"

namespace endohaptics::sim {

//! What the tool touches on one joint.
enum class Environment : std::uint8_t {
  free_space = 0,  //!< nothing: contact force is always 0
  load_cell,       //!< stiff linear spring-damper (the appendix E load cell)
  tissue,          //!< soft Hunt-Crossley contact (a finger, synthetic skin)
};

//! Human-readable name of an environment.
[[nodiscard]] constexpr std::string_view to_string(Environment environment) noexcept {
  switch (environment) {
    case Environment::free_space:
      return "free_space";
    case Environment::load_cell:
      return "load_cell";
    case Environment::tissue:
      return "tissue";
  }
  return "unknown environment";
}

//! Outcome of `SimulatedRig::advance`. On anything but `ok` the rig is left untouched.
enum class SimStatus : std::uint8_t {
  ok = 0,
  invalid_duration,  //!< NaN, +-Inf or negative time step
};

//! Human-readable name of a status, for logs.
[[nodiscard]] constexpr std::string_view to_string(SimStatus status) noexcept {
  switch (status) {
    case SimStatus::ok:
      return "ok";
    case SimStatus::invalid_duration:
      return "non-finite or negative duration";
  }
  return "unknown status";
}

//! Motor, gearhead and encoder of one joint (maxon A-max 22 + GP 22 + encoder MR, worksheet 2.4).
template <typename Scalar = double>
struct MotorParameters {
  Scalar torque_constant = Scalar(0.0171);        //!< kt, N m/A (= back-EMF constant, V s/rad)
  Scalar terminal_resistance = Scalar(14.0);      //!< R, ohm
  Scalar terminal_inductance = Scalar(0.891e-3);  //!< L, H
  Scalar rotor_inertia = Scalar(4.13e-7);         //!< J_m, kg m^2 at the motor shaft
  Scalar gear_ratio = Scalar(76000.0 / 2048.0);   //!< N, motor turns per output turn
  int encoder_counts = 512;                       //!< CPT, counts per motor turn (x4 quadrature)
};

//! EndoWrist side of one joint: tendon, play, inertia, friction (table 5.2), tool lever, range.
template <typename Scalar = double>
struct TransmissionParameters {
  Scalar joint_inertia = Scalar(2e-5);     //!< J_j, kg m^2 in gear-output coordinates
  Scalar tendon_stiffness = Scalar(5.0);   //!< k_t, N m/rad between gear output and joint
  Scalar tendon_damping = Scalar(4e-3);    //!< c_t, N m s/rad (acts only while engaged)
  Scalar backlash = Scalar(0.01745);       //!< total play (gearhead + adapter), rad
  Scalar static_friction = Scalar(0.2);    //!< K_s, A-equivalent: breakaway at standstill
  Scalar coulomb_friction = Scalar(0.18);  //!< K_c, A-equivalent while sliding (<= K_s)
  Scalar viscous_friction = Scalar(0.01);  //!< F_mu, A s/rad while sliding
  Scalar lever_arm = Scalar(0.18);         //!< r, m: tip force = joint torque / r
  Scalar position_min = Scalar(-1.02796);  //!< rad, setpoints are clamped to [min, max]
  Scalar position_max = Scalar(1.02796);   //!< rad
};

//! The table 5.3 cascade of one joint, in SI units (ESCON units: docs/models/sim.md).
template <typename Scalar = double>
struct ControllerParameters {
  Scalar position_gain = Scalar(10.0);       //!< Kp, (rad/s)/rad on the gear output (FPGA)
  Scalar speed_limit = Scalar(1.4);          //!< |speed reference| max, rad/s gear output
  Scalar acceleration_limit = Scalar(10.0);  //!< ESCON speed ramp, rad/s^2 gear output
  Scalar speed_gain = Scalar(0.426 / (1000.0 * std::numbers::pi / 30.0));  //!< A s/rad, motor
  Scalar speed_integral_time = Scalar(28e-3);                              //!< Ti speed, s
  Scalar current_gain = Scalar(1.121);                                     //!< V/A
  Scalar current_integral_time = Scalar(38e-6);                            //!< Ti current, s
  Scalar current_limit = Scalar(2.0);    //!< |current reference| max, A
  Scalar supply_voltage = Scalar(24.0);  //!< |terminal voltage| max, V
};

//! The contact environment of one joint. Contact when direction*(q - contact_position) > 0.
template <typename Scalar = double>
struct ContactParameters {
  Environment environment = Environment::free_space;  //!< which model applies
  Scalar contact_position = Scalar(0.3);              //!< rad, joint position at first touch
  int direction = 1;                                  //!< +1: obstacle above, -1: below
  Scalar load_cell_stiffness = Scalar(50.0);          //!< N m/rad (joint side)
  Scalar load_cell_damping = Scalar(6e-3);            //!< N m s/rad
  Scalar tissue_stiffness = Scalar(5.0);              //!< Hunt-Crossley k, N m/rad^n
  Scalar tissue_exponent = Scalar(1.5);               //!< Hunt-Crossley n (>= 1)
  Scalar tissue_damping = Scalar(0.5);                //!< Hunt-Crossley alpha, s/rad
};

//! Everything about one joint.
template <typename Scalar = double>
struct JointConfig {
  MotorParameters<Scalar> motor;                //!< motor, gearhead and encoder
  TransmissionParameters<Scalar> transmission;  //!< tendon, play, inertia, friction
  ControllerParameters<Scalar> controller;      //!< table 5.3 control cascade
  ContactParameters<Scalar> contact;            //!< contact environment
};

//! The whole rig: per-joint parameters (motor order roll, pitch, clamp1, clamp2) and the rates.
template <int N = 4, typename Scalar = double>
struct RigConfig {
  static_assert(N >= 1 && N <= 8, "the sbRIO protocol carries 1 to 8 motors");
  static_assert(std::is_floating_point_v<Scalar>, "RigConfig Scalar must be floating point");

  //! Per-joint parameters, motor order.
  std::array<JointConfig<Scalar>, static_cast<std::size_t>(N)> joints{};
  Scalar position_rate = Scalar(2000.0);  //!< Hz, FPGA P position loop and sbRIO sampling
  Scalar speed_rate = Scalar(5360.0);     //!< Hz, ESCON PI speed loop
  Scalar current_rate = Scalar(53600.0);  //!< Hz, ESCON PI current loop (integer multiple)
  int plant_substeps = 1;                 //!< mechanical sub-steps per current-loop period
  int velocity_window = 20;               //!< position samples in the reported velocity (1..64)
  Scalar current_filter_cutoff = Scalar(100.0);  //!< Hz, sbRIO first-order low-pass on the current
  //! +-1: the sign of the current the sbRIO reports relative to the physical one (positive
  //! current drives positive motion). The 2016 rig reports it negated on every motor (the current
  //! opposes the position error in 40 of its 41 logs: docs/models.md, "Current direction"), so
  //! endowrist_2016_rig() sets -1 and the estimator's default current_sign (-1) matches it.
  int reported_current_sign = 1;

  //! Throws Error naming the first invalid field and its value.
  void validate() const;
};

namespace detail::rig {

template <typename Scalar>
void require(bool ok, const std::string& field, Scalar value, std::string_view rule) {
  if (!ok) {
    ENDOHAPTICS_THROW(Error("RigConfig: " + field + " must be " + std::string(rule) + ", got " +
                            endohaptics::detail::format_number(value)));
  }
}

template <typename Scalar>
void positive(Scalar value, const std::string& field) {
  require(std::isfinite(value) && value > 0, field, value, "finite and > 0");
}

template <typename Scalar>
void non_negative(Scalar value, const std::string& field) {
  require(std::isfinite(value) && value >= 0, field, value, "finite and >= 0");
}

template <typename Scalar>
[[nodiscard]] constexpr Scalar sign(Scalar x) noexcept {
  return x > 0 ? Scalar(1) : (x < 0 ? Scalar(-1) : Scalar(0));
}

//! Per-joint constants derived once from the configuration.
template <typename Scalar>
struct JointConstants {
  Scalar output_torque_per_amp{};  //!< kt N, N m/A at the gear output
  Scalar motor_inertia_output{};   //!< J_m N^2, kg m^2
  Scalar current_decay{};          //!< exp(-R h / L)
  Scalar counts_per_radian{};      //!< x4 counts per rad of gear output
  Scalar radians_per_count{};      //!< 2 pi / (4 CPT N)
  Scalar static_torque{};          //!< K_s kt N, N m
  Scalar coulomb_torque{};         //!< K_c kt N, N m
  Scalar viscous_torque{};         //!< F_mu kt N, N m s/rad
};

//! Evolving state of one joint.
template <typename Scalar>
struct JointState {
  // Plant.
  Scalar motor_position{};  //!< gear output angle (motor angle / N), rad
  Scalar motor_velocity{};  //!< rad/s gear output
  Scalar joint_position{};  //!< rad
  Scalar joint_velocity{};  //!< rad/s
  Scalar current{};         //!< A
  Scalar contact_torque{};  //!< N m, >= 0 magnitude
  bool stuck = true;        //!< joint held by static friction
  // Controllers.
  bool enabled = false;
  Scalar setpoint{};           //!< rad, clamped
  Scalar speed_target{};       //!< rad/s gear output, position loop output
  Scalar speed_reference{};    //!< rad/s gear output, after the ESCON ramp
  Scalar speed_integral{};     //!< rad/s motor shaft (integrated error * T / Ti)
  Scalar current_reference{};  //!< A
  Scalar current_integral{};   //!< A
  Scalar voltage{};            //!< V
  // sbRIO report.
  std::array<Scalar, 64> history{};  //!< reported positions at the position rate (ring)
  int history_size = 0;
  int history_head = 0;
  Scalar reported_position{};
  Scalar reported_velocity{};
  Scalar filtered_current{};
};

}  // namespace detail::rig

template <int N, typename Scalar>
void RigConfig<N, Scalar>::validate() const {
  using detail::rig::non_negative;
  using detail::rig::positive;
  using detail::rig::require;
  positive(position_rate, "position_rate (Hz)");
  positive(speed_rate, "speed_rate (Hz)");
  positive(current_rate, "current_rate (Hz)");
  require(current_rate >= speed_rate && speed_rate >= position_rate, "speed_rate (Hz)", speed_rate,
          "between position_rate and current_rate");
  const Scalar ratio = current_rate / speed_rate;
  require(std::fabs(ratio - std::round(ratio)) < Scalar(1e-3), "current_rate / speed_rate", ratio,
          "an integer");
  require(plant_substeps >= 1 && plant_substeps <= 64, "plant_substeps", plant_substeps,
          "in 1..64");
  require(velocity_window >= 1 && velocity_window <= 63, "velocity_window", velocity_window,
          "in 1..63");
  positive(current_filter_cutoff, "current_filter_cutoff (Hz)");
  require(reported_current_sign == 1 || reported_current_sign == -1, "reported_current_sign",
          reported_current_sign, "+1 or -1");
  for (int j = 0; j < N; ++j) {
    const auto& c = joints[static_cast<std::size_t>(j)];
    const std::string p = "joints[" + std::to_string(j) + "].";
    positive(c.motor.torque_constant, p + "motor.torque_constant (N m/A)");
    positive(c.motor.terminal_resistance, p + "motor.terminal_resistance (ohm)");
    positive(c.motor.terminal_inductance, p + "motor.terminal_inductance (H)");
    positive(c.motor.rotor_inertia, p + "motor.rotor_inertia (kg m^2)");
    positive(c.motor.gear_ratio, p + "motor.gear_ratio");
    require(c.motor.encoder_counts > 0, p + "motor.encoder_counts", c.motor.encoder_counts, "> 0");
    const auto& t = c.transmission;
    positive(t.joint_inertia, p + "transmission.joint_inertia (kg m^2)");
    positive(t.tendon_stiffness, p + "transmission.tendon_stiffness (N m/rad)");
    non_negative(t.tendon_damping, p + "transmission.tendon_damping (N m s/rad)");
    non_negative(t.backlash, p + "transmission.backlash (rad)");
    non_negative(t.static_friction, p + "transmission.static_friction (A)");
    non_negative(t.coulomb_friction, p + "transmission.coulomb_friction (A)");
    require(t.coulomb_friction <= t.static_friction, p + "transmission.coulomb_friction (A)",
            t.coulomb_friction, "<= static_friction");
    non_negative(t.viscous_friction, p + "transmission.viscous_friction (A s/rad)");
    positive(t.lever_arm, p + "transmission.lever_arm (m)");
    require(std::isfinite(t.position_min) && std::isfinite(t.position_max) &&
                t.position_min < t.position_max,
            p + "transmission.position_min (rad)", t.position_min, "finite and < position_max");
    const auto& k = c.controller;
    positive(k.position_gain, p + "controller.position_gain (1/s)");
    positive(k.speed_limit, p + "controller.speed_limit (rad/s)");
    positive(k.acceleration_limit, p + "controller.acceleration_limit (rad/s^2)");
    positive(k.speed_gain, p + "controller.speed_gain (A s/rad)");
    positive(k.speed_integral_time, p + "controller.speed_integral_time (s)");
    positive(k.current_gain, p + "controller.current_gain (V/A)");
    positive(k.current_integral_time, p + "controller.current_integral_time (s)");
    positive(k.current_limit, p + "controller.current_limit (A)");
    positive(k.supply_voltage, p + "controller.supply_voltage (V)");
    const auto& e = c.contact;
    require(e.environment == Environment::free_space || e.environment == Environment::load_cell ||
                e.environment == Environment::tissue,
            p + "contact.environment", static_cast<int>(e.environment), "a listed Environment");
    require(std::isfinite(e.contact_position), p + "contact.contact_position (rad)",
            e.contact_position, "finite");
    require(e.direction == 1 || e.direction == -1, p + "contact.direction", e.direction,
            "+1 or -1");
    positive(e.load_cell_stiffness, p + "contact.load_cell_stiffness (N m/rad)");
    non_negative(e.load_cell_damping, p + "contact.load_cell_damping (N m s/rad)");
    positive(e.tissue_stiffness, p + "contact.tissue_stiffness (N m/rad^n)");
    require(std::isfinite(e.tissue_exponent) && e.tissue_exponent >= 1,
            p + "contact.tissue_exponent", e.tissue_exponent, "finite and >= 1");
    non_negative(e.tissue_damping, p + "contact.tissue_damping (s/rad)");
  }
}

//! The 2016 rig with every default from the worksheet and the 2016 logs (docs/models/sim.md).
//! Motor order roll, pitch, clamp1, clamp2; joints beyond 4 repeat clamp2's parameters. Every
//! joint gets `env`, touching at +0.3 rad (direction +1), except clamp 2, touching at -0.3 rad
//! (direction -1): the mapping drives the jaws in mirror (eq. 5.9, P_clamp2 = -P_clamp1), so a
//! grasp closes both onto the object.
template <int N = 4, typename Scalar = double>
[[nodiscard]] RigConfig<N, Scalar> endowrist_2016_rig(Environment env = Environment::tissue) {
  RigConfig<N, Scalar> config;
  config.reported_current_sign = -1;  // the 2016 sbRIO reports the current negated
  // Per joint: K_s, K_c [A], F_mu [A s/rad], lever [m], tendon [N m/rad], load cell [N m/rad],
  // tissue k [N m/rad^1.5]. Sources and derivations: docs/models/sim.md, "Parameters".
  struct Preset {
    double ks, kc, fv, lever, tendon, load_cell, tissue;
  };
  constexpr std::array<Preset, 4> presets{{
      {0.13, 0.065, 0.025, 0.18, 5.0, 50.0, 5.0},  // roll (table 5.2 says 0.7 A: see docs)
      {0.17, 0.15, 0.008, 0.18, 5.0, 50.0, 5.0},   // pitch (table 5.2, app. E.1.2)
      {0.21, 0.19, 0.01, 0.32, 8.5, 85.0, 10.0},   // clamp1 (table 5.2 "yaw", app. E.1.1)
      {0.20, 0.18, 0.01, 0.32, 8.5, 85.0, 10.0},   // clamp2 (table 5.2 "clamp")
  }};
  for (int j = 0; j < N; ++j) {
    const Preset& p = presets[static_cast<std::size_t>(std::min(j, 3))];
    auto& c = config.joints[static_cast<std::size_t>(j)];
    c.transmission.static_friction = static_cast<Scalar>(p.ks);
    c.transmission.coulomb_friction = static_cast<Scalar>(p.kc);
    c.transmission.viscous_friction = static_cast<Scalar>(p.fv);
    c.transmission.lever_arm = static_cast<Scalar>(p.lever);
    c.transmission.tendon_stiffness = static_cast<Scalar>(p.tendon);
    // Damping ratio ~0.2 of the tendon mode and ~0.1 of the load-cell mode on J_j.
    c.transmission.tendon_damping =
        static_cast<Scalar>(0.4 * std::sqrt(p.tendon * double(c.transmission.joint_inertia)));
    c.contact.environment = env;
    if (j >= 3) {  // clamp 2 (and the joints that repeat it)
      c.contact.contact_position = static_cast<Scalar>(-0.3);
      c.contact.direction = -1;
    }
    c.contact.load_cell_stiffness = static_cast<Scalar>(p.load_cell);
    c.contact.load_cell_damping =
        static_cast<Scalar>(0.2 * std::sqrt(p.load_cell * double(c.transmission.joint_inertia)));
    c.contact.tissue_stiffness = static_cast<Scalar>(p.tissue);
  }
  return config;
}

//! The true (unmeasurable) signals of the rig, per joint.
template <int N = 4, typename Scalar = double>
struct RigTruth {
  //! One value per joint, motor order.
  using Vector = Eigen::Matrix<Scalar, N, 1>;
  Vector joint_position = Vector::Zero();  //!< rad (gear-output coordinates, "motor side")
  Vector motor_velocity = Vector::Zero();  //!< rad/s (gear output)
  Vector motor_current = Vector::Zero();   //!< A, unfiltered
  Vector contact_force = Vector::Zero();   //!< N at the tool, >= 0 (pushes)
  //! N at the tool, signed: the contact's force along the joint's positive setpoint
  //! (-direction x contact_force), the convention of ForceEstimator and map_force.
  Vector external_force = Vector::Zero();
};

//! The simulated rig. Not thread-safe; one instance per rig. advance() is the real-time path.
template <int N = 4, typename Scalar = double>
class SimulatedRig {
  static_assert(N >= 1 && N <= 8, "the sbRIO protocol carries 1 to 8 motors");
  static_assert(std::is_floating_point_v<Scalar>, "SimulatedRig Scalar must be floating point");

 public:
  using Config = RigConfig<N, Scalar>;  //!< rig parameters
  using Truth = RigTruth<N, Scalar>;    //!< true signals per joint
  //! Longest duration one advance() accepts, s (bounds the work of one call).
  static constexpr double max_advance_seconds = 1e6;

  //! Validates `config` (throws Error) and starts at rest at position 0, all motors disabled.
  explicit SimulatedRig(const Config& config) : config_(config) {
    config_.validate();
    h_ = Scalar(1) / config_.current_rate;
    speed_divider_ = static_cast<int>(std::lround(config_.current_rate / config_.speed_rate));
    speed_period_ = h_ * static_cast<Scalar>(speed_divider_);
    position_period_ = Scalar(1) / config_.position_rate;
    position_step_ = config_.position_rate / config_.current_rate;
    position_phase_ = Scalar(1);  // the position loop runs on the first tick
    filter_alpha_ = Scalar(1) - std::exp(-Scalar(2) * std::numbers::pi_v<Scalar> *
                                         config_.current_filter_cutoff / config_.position_rate);
    for (std::size_t j = 0; j < constants_.size(); ++j) {
      const auto& m = config_.joints[j].motor;
      const auto& t = config_.joints[j].transmission;
      auto& c = constants_[j];
      c.output_torque_per_amp = m.torque_constant * m.gear_ratio;
      c.motor_inertia_output = m.rotor_inertia * m.gear_ratio * m.gear_ratio;
      c.current_decay = std::exp(-m.terminal_resistance * h_ / m.terminal_inductance);
      c.counts_per_radian = Scalar(4) * static_cast<Scalar>(m.encoder_counts) * m.gear_ratio /
                            (Scalar(2) * std::numbers::pi_v<Scalar>);
      c.radians_per_count = Scalar(1) / c.counts_per_radian;
      c.static_torque = t.static_friction * c.output_torque_per_amp;
      c.coulomb_torque = t.coulomb_friction * c.output_torque_per_amp;
      c.viscous_torque = t.viscous_friction * c.output_torque_per_amp;
    }
    update_truth();
  }

  //! Sets the setpoints (clamped to each joint's range; non-finite ones are ignored) and enable
  //! bits (bits >= N ignored). A motor follows only while its bit is set; disabled: current 0.
  void command(const protocol::MotorSetpoint<N>& setpoint) noexcept {
    for (int j = 0; j < N; ++j) {
      auto& s = joints_[static_cast<std::size_t>(j)];
      const auto& t = config_.joints[static_cast<std::size_t>(j)].transmission;
      const double p = setpoint.position[j];
      if (std::isfinite(p)) {
        s.setpoint = std::clamp(static_cast<Scalar>(p), t.position_min, t.position_max);
      }
      const bool enable = ((setpoint.enable_mask >> j) & 1u) != 0;
      if (enable && !s.enabled) {  // the ESCON starts from clean integrators
        s.speed_reference = Scalar(0);
        s.speed_integral = Scalar(0);
        s.current_integral = Scalar(0);
      }
      s.enabled = enable;
    }
  }

  //! Runs the plant and the loops for `seconds` (>= 0; the part of a current-loop period left
  //! over is carried to the next call). NaN, Inf, negative or > max_advance_seconds: returns
  //! invalid_duration and changes nothing. Allocation-free; ~53,600 ticks per simulated second.
  [[nodiscard]] SimStatus advance(Scalar seconds) noexcept {
    if (!std::isfinite(seconds) || seconds < 0 ||
        static_cast<double>(seconds) > max_advance_seconds) {
      return SimStatus::invalid_duration;
    }
    const double total = static_cast<double>(carry_) + static_cast<double>(seconds);
    const double h = static_cast<double>(h_);
    auto n = static_cast<std::uint64_t>(std::floor(total / h));
    for (std::uint64_t k = 0; k < n; ++k) tick();
    ticks_ += n;
    carry_ = static_cast<Scalar>(std::clamp(total - static_cast<double>(n) * h, 0.0, h));
    update_truth();
    return SimStatus::ok;
  }

  //! What the sbRIO reports: x4 encoder position, windowed velocity, filtered current, mask.
  [[nodiscard]] protocol::MotorState<N> state() const noexcept {
    protocol::MotorState<N> out;
    for (int j = 0; j < N; ++j) {
      const auto& s = joints_[static_cast<std::size_t>(j)];
      out.position[j] = static_cast<double>(encoder_position(j));
      out.velocity[j] = static_cast<double>(s.reported_velocity);
      out.current[j] = static_cast<double>(config_.reported_current_sign) *
                       static_cast<double>(s.filtered_current);
      if (s.enabled) out.active_mask = static_cast<std::uint8_t>(out.active_mask | (1u << j));
    }
    return out;
  }

  //! The true (unmeasurable) signals.
  [[nodiscard]] const Truth& truth() const noexcept { return truth_; }

  //! Seconds simulated since construction (the sum of all valid `advance` durations).
  [[nodiscard]] Scalar time() const noexcept {
    return static_cast<Scalar>(static_cast<double>(ticks_) * static_cast<double>(h_) +
                               static_cast<double>(carry_));
  }

  //! Switches the environment of `joint` at run time. Precondition: 0 <= joint < N (else ignored).
  void set_environment(int joint, Environment env) noexcept {
    if (joint < 0 || joint >= N) return;
    auto& contact = config_.joints[static_cast<std::size_t>(joint)].contact;
    contact.environment = env;
    if (env == Environment::free_space) {
      joints_[static_cast<std::size_t>(joint)].contact_torque = Scalar(0);
      truth_.contact_force[joint] = Scalar(0);
      truth_.external_force[joint] = Scalar(0);
    }
  }

  //! The validated configuration (with the run-time environment changes).
  [[nodiscard]] const Config& config() const noexcept { return config_; }

  //! Encoder resolution of `joint`: rad of gear output per x4 count, 2 pi / (4 CPT N).
  //! Precondition: 0 <= joint < N.
  [[nodiscard]] Scalar encoder_resolution(int joint) const noexcept {
    return constants_[static_cast<std::size_t>(joint)].radians_per_count;
  }

 private:
  using Constants = detail::rig::JointConstants<Scalar>;
  using State = detail::rig::JointState<Scalar>;
  static constexpr int history_capacity = 64;

  // One current-loop period: the loops sample at its start, then the plant integrates over it.
  void tick() noexcept {
    position_phase_ += position_step_;
    const bool run_position = position_phase_ >= Scalar(1);
    if (run_position) position_phase_ -= Scalar(1);
    const bool run_speed = speed_counter_ == 0;
    speed_counter_ = speed_counter_ + 1 == speed_divider_ ? 0 : speed_counter_ + 1;
    for (int j = 0; j < N; ++j) {
      if (run_position) position_loop(j);
      if (run_speed) speed_loop(j);
      current_loop_and_plant(j);
    }
  }

  // FPGA at position_rate: encoder count, reported velocity and current, P position control.
  void position_loop(int j) noexcept {
    const auto ju = static_cast<std::size_t>(j);
    auto& s = joints_[ju];
    const auto& k = config_.joints[ju].controller;
    const Scalar position = encoder_position(j);
    const int window = std::min(s.history_size, config_.velocity_window);
    if (window > 0) {
      const int oldest = (s.history_head - window + history_capacity) % history_capacity;
      s.reported_velocity = (position - s.history[static_cast<std::size_t>(oldest)]) /
                            (static_cast<Scalar>(window) * position_period_);
    }
    s.history[static_cast<std::size_t>(s.history_head)] = position;
    s.history_head = (s.history_head + 1) % history_capacity;
    s.history_size = std::min(s.history_size + 1, history_capacity);
    s.reported_position = position;
    s.filtered_current += filter_alpha_ * (s.current - s.filtered_current);
    s.speed_target = s.enabled ? std::clamp(k.position_gain * (s.setpoint - position),
                                            -k.speed_limit, k.speed_limit)
                               : Scalar(0);
  }

  // ESCON PI speed at speed_rate: ramp-limited reference, conditional-integration anti-windup,
  // current limit. Error in rad/s at the motor shaft.
  void speed_loop(int j) noexcept {
    const auto ju = static_cast<std::size_t>(j);
    auto& s = joints_[ju];
    const auto& k = config_.joints[ju].controller;
    if (!s.enabled) {
      s.speed_reference = s.speed_integral = s.current_reference = Scalar(0);
      return;
    }
    const Scalar step = k.acceleration_limit * speed_period_;
    s.speed_reference += std::clamp(s.speed_target - s.speed_reference, -step, step);
    const Scalar ratio = config_.joints[ju].motor.gear_ratio;
    const Scalar error = (s.speed_reference - s.motor_velocity) * ratio;
    const Scalar unsaturated = k.speed_gain * (error + s.speed_integral);
    const bool wind_up = (unsaturated > k.current_limit && error > 0) ||
                         (unsaturated < -k.current_limit && error < 0);
    if (!wind_up) {
      const Scalar bound = k.current_limit / k.speed_gain;
      s.speed_integral = std::clamp(
          s.speed_integral + error * speed_period_ / k.speed_integral_time, -bound, bound);
    }
    s.current_reference =
        std::clamp(k.speed_gain * (error + s.speed_integral), -k.current_limit, k.current_limit);
  }

  // ESCON PI current at current_rate with voltage saturation, then the plant over one period.
  void current_loop_and_plant(int j) noexcept {
    const auto ju = static_cast<std::size_t>(j);
    auto& s = joints_[ju];
    const auto& c = constants_[ju];
    const auto& cfg = config_.joints[ju];
    const auto& m = cfg.motor;
    const auto& k = cfg.controller;
    if (s.enabled) {
      const Scalar error = s.current_reference - s.current;
      const Scalar unsaturated = k.current_gain * (error + s.current_integral);
      const bool wind_up = (unsaturated > k.supply_voltage && error > 0) ||
                           (unsaturated < -k.supply_voltage && error < 0);
      if (!wind_up) {
        const Scalar bound = k.supply_voltage / k.current_gain;
        s.current_integral =
            std::clamp(s.current_integral + error * h_ / k.current_integral_time, -bound, bound);
      }
      s.voltage = std::clamp(k.current_gain * (error + s.current_integral), -k.supply_voltage,
                             k.supply_voltage);
      // L di/dt = u - R i - kt w, exact over h with u and the back-EMF held.
      const Scalar back_emf = m.torque_constant * s.motor_velocity * m.gear_ratio;
      const Scalar steady = (s.voltage - back_emf) / m.terminal_resistance;
      s.current = steady + (s.current - steady) * c.current_decay;
    } else {  // bridge off: no current, the motor coasts
      s.current = s.voltage = s.current_integral = Scalar(0);
    }
    mechanics(s, c, cfg, h_ / static_cast<Scalar>(config_.plant_substeps));
    for (int sub = 1; sub < config_.plant_substeps; ++sub) {
      mechanics(s, c, cfg, h_ / static_cast<Scalar>(config_.plant_substeps));
    }
  }

  // Semi-implicit Euler over dt: motor inertia -- play + tendon spring-damper -- joint inertia
  // with stick-slip friction and the contact. Velocities first, then positions.
  static void mechanics(State& s, const Constants& c, const JointConfig<Scalar>& cfg,
                        Scalar dt) noexcept {
    const auto& t = cfg.transmission;
    // Tendon through the play: pushes only while engaged, never pulls across the gap.
    const Scalar half_play = t.backlash / Scalar(2);
    const Scalar delta = s.motor_position - s.joint_position;
    const Scalar relative_velocity = s.motor_velocity - s.joint_velocity;
    Scalar tendon = Scalar(0);
    if (delta > half_play) {
      tendon = std::max(Scalar(0), t.tendon_stiffness * (delta - half_play) +
                                       t.tendon_damping * relative_velocity);
    } else if (delta < -half_play) {
      tendon = std::min(Scalar(0), t.tendon_stiffness * (delta + half_play) +
                                       t.tendon_damping * relative_velocity);
    }
    // Contact (unilateral): magnitude f >= 0 acting against `direction`.
    const auto& e = cfg.contact;
    const auto dir = static_cast<Scalar>(e.direction);
    const Scalar depth = dir * (s.joint_position - e.contact_position);
    Scalar contact = Scalar(0);
    if (depth > 0) {
      const Scalar rate = dir * s.joint_velocity;
      if (e.environment == Environment::load_cell) {
        contact = std::max(Scalar(0), e.load_cell_stiffness * depth + e.load_cell_damping * rate);
      } else if (e.environment == Environment::tissue) {
        const Scalar power = e.tissue_exponent == Scalar(1.5) ? depth * std::sqrt(depth)
                                                              : std::pow(depth, e.tissue_exponent);
        contact =
            std::max(Scalar(0), e.tissue_stiffness * power * (Scalar(1) + e.tissue_damping * rate));
      }
    }
    s.contact_torque = contact;
    // Motor side (gear-output coordinates): J_m N^2 dw/dt = kt N i - tendon.
    s.motor_velocity +=
        dt * (c.output_torque_per_amp * s.current - tendon) / c.motor_inertia_output;
    // Joint side: stick-slip (Karnopp-type with zero-velocity capture, no chatter).
    const Scalar drive = tendon - dir * contact;
    if (s.stuck && std::fabs(drive) > c.static_torque) s.stuck = false;
    if (s.stuck) {
      s.joint_velocity = Scalar(0);
    } else {
      const Scalar v = s.joint_velocity;
      const Scalar direction = v != 0 ? detail::rig::sign(v) : detail::rig::sign(drive);
      const Scalar friction = direction * (c.coulomb_torque + c.viscous_torque * std::fabs(v));
      const Scalar next = v + dt * (drive - friction) / t.joint_inertia;
      if (next * direction <= 0) {  // friction would reverse the motion: the joint stops
        s.joint_velocity = Scalar(0);
        s.stuck = std::fabs(drive) <= c.static_torque;
      } else {
        s.joint_velocity = next;
      }
    }
    s.motor_position += dt * s.motor_velocity;
    s.joint_position += dt * s.joint_velocity;
  }

  [[nodiscard]] Scalar encoder_position(int j) const noexcept {
    const auto& c = constants_[static_cast<std::size_t>(j)];
    const Scalar count =
        std::floor(joints_[static_cast<std::size_t>(j)].motor_position * c.counts_per_radian);
    return count * c.radians_per_count;
  }

  void update_truth() noexcept {
    for (int j = 0; j < N; ++j) {
      const auto ju = static_cast<std::size_t>(j);
      const auto& s = joints_[ju];
      truth_.joint_position[j] = s.joint_position;
      truth_.motor_velocity[j] = s.motor_velocity;
      truth_.motor_current[j] = s.current;
      truth_.contact_force[j] = s.contact_torque / config_.joints[ju].transmission.lever_arm;
      truth_.external_force[j] =
          -static_cast<Scalar>(config_.joints[ju].contact.direction) * truth_.contact_force[j];
    }
  }

  Config config_;
  std::array<Constants, static_cast<std::size_t>(N)> constants_{};
  std::array<State, static_cast<std::size_t>(N)> joints_{};
  Truth truth_{};
  Scalar h_{};                // current-loop period, s
  Scalar speed_period_{};     // s
  Scalar position_period_{};  // s
  Scalar position_step_{};    // position periods per tick
  Scalar position_phase_{};   // position periods elapsed since the last position-loop run
  Scalar filter_alpha_{};     // current low-pass coefficient at the position rate
  int speed_divider_ = 10;    // ticks per speed-loop period
  int speed_counter_ = 0;
  std::uint64_t ticks_ = 0;
  Scalar carry_{};  // s of an unfinished current-loop period
};

}  // namespace endohaptics::sim
