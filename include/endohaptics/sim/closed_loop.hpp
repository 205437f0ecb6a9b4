//! @file
//! ClosedLoop: force-feedback teleoperation with the operator in the loop, deterministic on a
//! virtual clock and faster than real time. HapticDeviceModel (the table 5.1 arm holding a
//! Touch-like stylus, pressing into a contact and holding) -> the real TeleopLoop (eqs. 5.8/5.9
//! mapping, watchdog, optional passivity layer) -> FaultInjectingTransport (loss) over DelayLine
//! (delay, jitter), both directions -> SbrioEmulator -> SimulatedRig with a contact on clamp 1
//! (soft tissue or a stiff stop). The force fed back (ForceSource) is an ideal sensor's (the rig's
//! true contact force sampled when the sbRIO answers and carried with that state packet, so it is
//! delayed and lost with it) or the bridge's sensorless estimate from what the sbRIO reports
//! (an identified clamp model, or the 2016 preset), computed at the PC as the bridge does.
//! Units: s, m, rad, N, J. docs/passivity.md.
#pragma once

#include <Eigen/Core>
#include <algorithm>
#include <array>
#include <chrono>
#include <cmath>
#include <cstdint>
#include <limits>
#include <optional>
#include <span>
#include <string>
#include <string_view>
#include <vector>

#include "endohaptics/core/clock.hpp"
#include "endohaptics/core/error.hpp"
#include "endohaptics/estimation/bridge_force_models.hpp"
#include "endohaptics/estimation/clamp_presets.hpp"
#include "endohaptics/estimation/force_estimator.hpp"
#include "endohaptics/estimation/paced_estimator.hpp"
#include "endohaptics/estimation/stiction_hold.hpp"
#include "endohaptics/kinematics/cylindrical_mapper.hpp"
#include "endohaptics/model/human_arm_model.hpp"
#include "endohaptics/sim/delay_line.hpp"
#include "endohaptics/sim/haptic_device_model.hpp"
#include "endohaptics/sim/sbrio_emulator.hpp"
#include "endohaptics/sim/simulated_rig.hpp"
#include "endohaptics/teleop/teleop_loop.hpp"
#include "endohaptics/transport/fault_injecting_transport.hpp"
#include "endohaptics/transport/in_memory_transport.hpp"

namespace endohaptics::sim {

//! What clamp 1 presses into.
enum class ContactKind : std::uint8_t {
  soft_tissue = 0,  //!< Hunt-Crossley tissue (the rig's clamp preset, 10 N m/rad^1.5)
  stiff_stop,       //!< linear stiff stop (the rig's load-cell preset, 85 N m/rad)
};

//! The contact's name ("soft tissue", "stiff stop").
[[nodiscard]] constexpr std::string_view to_string(ContactKind k) noexcept {
  return k == ContactKind::soft_tissue ? "soft tissue" : "stiff stop";
}

//! Where the force fed back comes from.
enum class ForceSource : std::uint8_t {
  sensor = 0,   //!< an ideal sensor: the rig's true force, carried with the state packet
  identified,   //!< the bridge's estimator with an identified clamp model (ClosedLoopConfig)
  preset_2016,  //!< the bridge's estimator with the 2016 preset (yaw2016: appendix C, gates)
};

//! The source's name ("sensor", "identified", "preset-2016").
[[nodiscard]] constexpr std::string_view to_string(ForceSource s) noexcept {
  switch (s) {
    case ForceSource::sensor:
      return "sensor";
    case ForceSource::identified:
      return "identified";
    case ForceSource::preset_2016:
      return "preset-2016";
  }
  return "unknown";
}

//! One closed-loop scenario.
struct ClosedLoopConfig {
  std::chrono::nanoseconds round_trip{0};  //!< network delay, both directions together
  std::chrono::nanoseconds jitter{0};      //!< extra uniform delay per direction, [0, jitter]
  double loss = 0.0;                       //!< probability a datagram is lost, each direction
  std::uint64_t seed = 1;                  //!< seeds the jitter and the loss
  ContactKind contact = ContactKind::stiff_stop;  //!< what clamp 1 presses into
  double stiffness = 0.0;          //!< N m/rad (stop) or N m/rad^1.5 (tissue); 0: the preset
  double contact_position = 0.15;  //!< rad, clamp 1 at first touch
  double press_depth = 0.025;      //!< m, how far beyond the touch the operator's intent goes
  double approach_start = 0.3;     //!< s
  double approach_time = 1.0;      //!< s
  //! Stylus N per tool N on the clamp channel (eq. 5.8's radial force_scale is twice this: the
  //! channel is (f_clamp2 - f_clamp1) / 2). A gain > 1 makes tissue forces perceptible.
  double force_gain = 4.0;
  double force_limit = 3.0;  //!< N, the mapper's channel and magnitude limits (Touch: 3.3 N peak)
  teleop::PassivityConfig passivity{};      //!< the loop's passivity layer
  DeviceParameters device{};                //!< the stylus
  model::HumanArmParameters<double> arm{};  //!< table 5.1
  teleop::TeleopLoopConfig loop{};  //!< period, timeout, safety (passivity taken from above)
  ForceSource force_source = ForceSource::sensor;  //!< what the loop renders
  //! ForceSource::identified: the clamp model both clamps run (as the bridge runs a clamp model
  //! file); required then, ignored otherwise.
  std::optional<estimation::BridgeJointModel> clamp_model{};
  //! Sensorless sources: the estimator's stiction memory (ForceEstimatorSettings::stick_travel,
  //! stick_play, stick_force) on every joint, with the simulated instrument's own constants
  //! (stiction_memory_settings), as the demo sets it for the emulator's instrument. Off: the
  //! estimate is passed on as the model gives it.
  bool stiction_memory = false;
  //! With stiction_memory: the memory also holds through zero beyond stiction_contact_level
  //! (ForceEstimatorSettings::stick_contact_level, same constants); without, it lets go when the
  //! estimate changes sign.
  bool stiction_through_zero = false;
  //! N per motor, with stiction_through_zero: the estimate's error bound in free motion
  //! (estimation::StictionHold's contact level); a held force within it is held only on the
  //! same side.
  estimation::MotorVector stiction_contact_level = estimation::MotorVector::Zero();

  //! Throws Error naming the field and value.
  void validate() const {
    if (!(loss >= 0.0 && loss <= 1.0)) {
      ENDOHAPTICS_THROW(Error("ClosedLoopConfig: loss must be in [0, 1], got " +
                              endohaptics::detail::format_number(loss)));
    }
    DelaySettings{round_trip / 2, jitter}.validate();
    if (!std::isfinite(stiffness) || stiffness < 0.0) {
      ENDOHAPTICS_THROW(Error("ClosedLoopConfig: stiffness must be >= 0 (0: preset), got " +
                              endohaptics::detail::format_number(stiffness)));
    }
    if (!std::isfinite(contact_position) || std::fabs(contact_position) > 1.0) {
      ENDOHAPTICS_THROW(Error("ClosedLoopConfig: contact_position must be in [-1, 1] rad, got " +
                              endohaptics::detail::format_number(contact_position)));
    }
    if (!std::isfinite(force_gain) || force_gain < 0.0 || !std::isfinite(force_limit) ||
        !(force_limit > 0.0)) {
      ENDOHAPTICS_THROW(
          Error("ClosedLoopConfig: force_gain must be >= 0 and force_limit > 0, got " +
                endohaptics::detail::format_number(force_gain) + " and " +
                endohaptics::detail::format_number(force_limit)));
    }
    if (force_source == ForceSource::identified && !clamp_model) {
      ENDOHAPTICS_THROW(Error("ClosedLoopConfig: force source identified needs a clamp_model"));
    }
    if (!std::isfinite(press_depth) || press_depth < 0.0 || press_depth > 0.1) {
      ENDOHAPTICS_THROW(Error("ClosedLoopConfig: press_depth must be in [0, 0.1] m, got " +
                              endohaptics::detail::format_number(press_depth)));
    }
  }
};

//! What one tick of the closed loop did (clamp 1 is the pressing joint).
struct ClosedLoopSample {
  double time = 0.0;                                        //!< s since the start
  teleop::TickStatus status = teleop::TickStatus::waiting;  //!< the loop's tick status
  double stylus_force = 0.0;       //!< N, device force along +x (the radius: pushes the hand back)
  double stylus_position = 0.0;    //!< m, stylus x (the radius)
  double commanded_force = 0.0;    //!< N, |force| the loop commanded (before the device's limit)
  double contact_force = 0.0;      //!< N at the tool, true, >= 0
  double estimated_force = 0.0;    //!< N at the tool, clamp 1's force the loop has (motor order)
  double true_stylus_force = 0.0;  //!< N, the stylus force the true tool forces map to (+x)
  double desired = 0.0;            //!< rad, clamp 1 setpoint the stylus maps to (range-clamped)
  double setpoint = 0.0;           //!< rad, clamp 1 setpoint sent
  double robot = 0.0;              //!< rad, clamp 1 true joint position
  double motor = 0.0;    //!< rad, clamp 1 motor (gear output) position as the sbRIO reports it
  double current = 0.0;  //!< A, clamp 1 motor current as the sbRIO reports it
  bool force_limited = false;            //!< a limit scaled the force this tick
  teleop::PassivityFigures passivity{};  //!< the loop's energy figures (observe/tdpa)
};

//! What a press-and-hold run shows (analyze_press). Forces in N at the stylus unless noted.
struct PressReport {
  bool contact = false;          //!< the tool touched (true contact force above 0.05 N)
  double onset = 0.0;            //!< s, first contact
  double first_peak = 0.0;       //!< N, largest |stylus force| in the first second of contact
  double peak_time = 0.0;        //!< s, when
  double decay_amplitude = 0.0;  //!< N, half the force's range 1.0 to 1.5 s after the peak
  double late_amplitude = 0.0;   //!< N, half the force's range over the last second
  //! J, lowest observer value (observe/tdpa modes): the combined observer, or with TDPA on
  //! per-direction observers the lowest of the two the controllers answer for
  double min_energy = 0.0;
  double max_force = 0.0;   //!< N, largest force the loop commanded
  double saturated = 0.0;   //!< fraction of ticks after contact with a force limit hit
  double hold_force = 0.0;  //!< N, mean stylus force over the last second
  //! N, mean over the last second of the stylus force the true tool forces map to (what an
  //! ideal sensor would render without the passivity layer): the hold felt should be near it.
  double true_hold_force = 0.0;
  double drift = 0.0;           //!< rad, clamp 1 |desired - sent| at the end
  double felt_stiffness = 0.0;  //!< N/m, hold force / operator's penetration (stylus)
  double true_stiffness = 0.0;  //!< N/m, the same for the robot's true penetration
  //! Felt / true hold force (hold_force / true_hold_force; 0 without a true hold force).
  [[nodiscard]] double felt_ratio() const noexcept {
    return true_hold_force > 1e-9 ? hold_force / true_hold_force : 0.0;
  }
  //! The oscillation fell below 10 % of the first peak within 1 s of it.
  [[nodiscard]] bool decays() const noexcept {
    return contact && decay_amplitude < 0.1 * first_peak;
  }
};

//! The ideal sensor: returns the tag (true force at the sbRIO's answer) of the newest state the
//! PC received. estimation::JointForceEstimator.
struct TaggedForceSensor {
  const estimation::MotorVector* newest;  //!< written by the link on each delivery
  //! Writes the force carried with the newest state; always succeeds.
  bool estimate(const estimation::MotorState4&, const estimation::MotorVector&,
                estimation::MotorVector& force) noexcept {
    force = *newest;
    return true;
  }
  void reset() noexcept {}  //!< stateless
};

//! The estimator's stiction memory for the simulated instrument `rig` (docs/models.md,
//! "Stiction memory"; the demo's numbers for the emulator's instrument, examples/demo.sh), per
//! joint from its physical constants only: a joint pressed into an object stays put while its
//! motor backs off through the static-friction band of the tendon's torque, 2 K_s k_tau N / k_t
//! of travel (stick_travel, rad); below the force the static friction holds against,
//! K_s k_tau N / lever (stick_force, N at the tool), also through the play (stick_play, the
//! transmission's backlash, rad). Writes those three into `settings` (index = Motor; the rig's
//! joints are in motor order).
template <int N>
void stiction_memory_settings(const RigConfig<N, double>& rig,
                              estimation::ForceEstimatorSettings<double>& settings) noexcept {
  static_assert(N >= 4, "roll, pitch and both clamps");
  for (int j = 0; j < 4; ++j) {
    const auto& joint = rig.joints[static_cast<std::size_t>(j)];
    const double static_torque = joint.transmission.static_friction * joint.motor.torque_constant *
                                 joint.motor.gear_ratio;  // N m
    settings.stick_travel[j] = 2.0 * static_torque / joint.transmission.tendon_stiffness;
    settings.stick_play[j] = joint.transmission.backlash;
    settings.stick_force[j] = static_torque / joint.transmission.lever_arm;
  }
}

//! The loop's estimator: the ideal sensor, or the bridge's (BridgeForceEstimator paced at 1 kHz
//! on the loop's clock, estimation::PacedEstimator, from the decoded sbRIO state only).
//! estimation::JointForceEstimator; neither copied nor moved (the pacer holds its address).
class LoopForceEstimator {
 public:
  using Clock = ManualClock;  //!< the loop's virtual clock
  //! `newest`: the sensor's tag (ForceSource::sensor); `stiction`: the stiction memory's
  //! settings (stiction_memory_settings), or null for none; `through_zero`: that memory holding
  //! through zero beyond `contact_level` (N per motor, the estimate's free-motion error bound;
  //! ForceEstimatorSettings::stick_contact_level). Throws Error on a model the bridge's estimator
  //! refuses.
  LoopForceEstimator(const estimation::MotorVector* newest, ForceSource source,
                     const std::optional<estimation::BridgeJointModel>& clamp, Clock& clock,
                     const estimation::ForceEstimatorSettings<double>* stiction = nullptr,
                     bool through_zero = false,
                     const estimation::MotorVector& contact_level = estimation::MotorVector::Zero())
      : sensor_{newest} {
    if (source == ForceSource::sensor) return;
    const auto models = source == ForceSource::identified
                            ? estimation::bridge_force_models(clamp)
                            : estimation::preset_force_models(estimation::ClampPreset::yaw2016);
    estimation::ForceEstimatorSettings<double> settings;
    settings.loop_period = 1e-3;
    if (stiction != nullptr) {
      settings.stick_travel = stiction->stick_travel;
      settings.stick_play = stiction->stick_play;
      settings.stick_force = stiction->stick_force;
      if (through_zero) settings.stick_contact_level = contact_level;
    }
    estimator_.emplace(models, estimation::bridge_estimator_settings(settings, models));
    paced_.emplace(*estimator_, clock, std::chrono::milliseconds(1));
  }
  LoopForceEstimator(const LoopForceEstimator&) = delete;             //!< the pacer points in
  LoopForceEstimator& operator=(const LoopForceEstimator&) = delete;  //!< the pacer points in

  //! JointForceEstimator: the sensor's tag, or the paced estimate.
  bool estimate(const estimation::MotorState4& measured, const estimation::MotorVector& setpoint,
                estimation::MotorVector& force) noexcept {
    if (!paced_) return sensor_.estimate(measured, setpoint, force);
    return paced_->estimate(measured, setpoint, force);
  }
  //! Forgets the model's history (the link came back).
  void reset() noexcept {
    if (paced_) paced_->reset();
  }

 private:
  TaggedForceSensor sensor_;
  std::optional<estimation::BridgeForceEstimator> estimator_;
  std::optional<estimation::PacedEstimator<estimation::BridgeForceEstimator, Clock>> paced_;
};

//! The whole loop. Large (the delay lines): create with std::make_unique. Single-threaded.
class ClosedLoop {
 public:
  using Rig = SimulatedRig<4>;               //!< the simulated EndoWrist
  using Tag = estimation::MotorVector;       //!< true external force carried with a state packet
  using Line = DelayLine<Tag>;               //!< one direction of the network
  using Queue = transport::DatagramQueue<>;  //!< what arrived and waits to be read

  //! The PC's end of the network (inside the loss injector).
  struct PcEnd {
    ClosedLoop* owner;  //!< the loop this end belongs to
    //! Puts the datagram on the forward line.
    transport::TransportStatus send(std::span<const std::byte> datagram) noexcept {
      (void)owner->forward_.push(datagram, owner->clock_.now(), Tag::Zero());
      return transport::TransportStatus::ok;
    }
    //! Runs the network and the sbRIO in virtual time until a state arrives or the deadline.
    template <transport::DatagramFilter F>
    transport::ReceiveResult receive(std::span<std::byte> buffer, std::chrono::nanoseconds timeout,
                                     F& filter) noexcept {
      if (owner->to_pc_.size() == 0) owner->run_until(owner->clock_.now() + timeout, true);
      transport::InMemoryTransport<> view(owner->unused_, owner->to_pc_);
      return view.receive(buffer, timeout, filter);
    }
    //! As above, accepting any datagram.
    transport::ReceiveResult receive(std::span<std::byte> buffer,
                                     std::chrono::nanoseconds timeout) noexcept {
      transport::AcceptAny any;
      return receive(buffer, timeout, any);
    }
  };

  //! The sbRIO's end (inside its loss injector): answers go on the backward line, tagged.
  struct SbrioEnd {
    ClosedLoop* owner;  //!< the loop this end belongs to
    //! Puts the answer on the backward line with the rig's true force now.
    transport::TransportStatus send(std::span<const std::byte> datagram) noexcept {
      (void)owner->backward_.push(datagram, owner->clock_.now(),
                                  owner->rig_.truth().external_force);
      return transport::TransportStatus::ok;
    }
    //! Reads what the forward line delivered (never waits).
    template <transport::DatagramFilter F>
    transport::ReceiveResult receive(std::span<std::byte> buffer, std::chrono::nanoseconds timeout,
                                     F& filter) noexcept {
      transport::InMemoryTransport<> view(owner->unused_, owner->to_sbrio_);
      return view.receive(buffer, timeout, filter);
    }
    //! As above, accepting any datagram.
    transport::ReceiveResult receive(std::span<std::byte> buffer,
                                     std::chrono::nanoseconds timeout) noexcept {
      transport::AcceptAny any;
      return receive(buffer, timeout, any);
    }
  };

  using PcTransport = transport::FaultInjectingTransport<PcEnd>;        //!< loss, forward
  using SbrioTransport = transport::FaultInjectingTransport<SbrioEnd>;  //!< loss, backward
  using Emulator = SbrioEmulator<SbrioTransport, Rig, ManualClock>;     //!< the sbRIO
  using Device = HapticDeviceModel<ManualClock>;                        //!< stylus and arm
  using Mapper = kinematics::CylindricalMapper<>;                       //!< eqs. 5.8/5.9
  //! The real TeleopLoop over the simulated network, stylus and sensor.
  using Loop = teleop::TeleopLoop<PcTransport, Device, LoopForceEstimator, Mapper, ManualClock>;

  //! Throws Error on an invalid configuration.
  explicit ClosedLoop(const ClosedLoopConfig& config)
      : config_((config.validate(), config)),
        rig_(rig_config(config)),
        forward_(DelaySettings{config.round_trip / 2, config.jitter}, config.seed),
        backward_(DelaySettings{config.round_trip - config.round_trip / 2, config.jitter},
                  config.seed + 1),
        pc_end_{this},
        sbrio_end_{this},
        pc_transport_(pc_end_, loss_rates(config.loss), config.seed + 2),
        sbrio_transport_(sbrio_end_, loss_rates(config.loss), config.seed + 3),
        emulator_(sbrio_transport_, rig_, clock_),
        device_(clock_, press_script(config), config.device, config.arm),
        stiction_(stiction_settings(rig_.config())),
        sensor_(&newest_force_, config.force_source, config.clamp_model, clock_,
                config.stiction_memory ? &stiction_ : nullptr, config.stiction_through_zero,
                config.stiction_contact_level),
        mapper_(mapping(config)),
        loop_(pc_transport_, device_, sensor_, mapper_, clock_, loop_config(config)),
        start_(clock_.now()) {}

  ClosedLoop(const ClosedLoop&) = delete;             //!< parts point at each other
  ClosedLoop& operator=(const ClosedLoop&) = delete;  //!< parts point at each other

  //! One loop period: a tick, then the network and the rig run to the next period's start.
  ClosedLoopSample step() noexcept {
    const auto tick_start = clock_.now();
    const teleop::TickResult r = loop_.tick();
    run_until(tick_start + loop_.config().period, false);
    emulator_.advance_to(clock_.now());
    ClosedLoopSample s;
    s.time = std::chrono::duration<double>(clock_.now() - start_).count();
    s.status = r.status;
    s.stylus_force = device_.force().x();
    s.stylus_position = device_.position().x();
    s.commanded_force = device_.commanded_norm();
    s.contact_force = rig_.truth().contact_force[clamp1];
    s.estimated_force = r.motor_force[clamp1];
    Eigen::Vector3d truth_force;
    if (mapper_.map_force(rig_.truth().external_force, truth_force).ok()) {
      s.true_stylus_force = truth_force.x();
    }
    s.desired = desired_clamp1();
    s.setpoint = r.setpoint[clamp1];
    s.robot = rig_.truth().joint_position[clamp1];
    const auto reported = rig_.state();
    s.motor = reported.position[clamp1];
    s.current = reported.current[clamp1];
    s.force_limited = r.force_limited;
    s.passivity = r.passivity;
    return s;
  }

  //! Runs `seconds` of loop periods, appending every sample to `out` (may allocate: offline).
  void run(double seconds, std::vector<ClosedLoopSample>& out) {
    const auto n = static_cast<std::size_t>(
        std::llround(seconds / std::chrono::duration<double>(loop_.config().period).count()));
    out.reserve(out.size() + n);
    for (std::size_t i = 0; i < n; ++i) out.push_back(step());
  }

  [[nodiscard]] const ClosedLoopConfig& config() const noexcept { return config_; }  //!< scenario
  [[nodiscard]] const Loop& loop() const noexcept { return loop_; }           //!< the TeleopLoop
  [[nodiscard]] const Rig& rig() const noexcept { return rig_; }              //!< the EndoWrist
  [[nodiscard]] const Device& device() const noexcept { return device_; }     //!< stylus and arm
  [[nodiscard]] const Mapper& mapper() const noexcept { return mapper_; }     //!< eqs. 5.8/5.9
  [[nodiscard]] const ManualClock& clock() const noexcept { return clock_; }  //!< virtual time
  //! Clamp 1's setpoint (rad) at the stylus x position `x` (m) on the press line (eq. 5.9).
  [[nodiscard]] double clamp1_at(double x) const noexcept {
    const auto& m = mapper_.config();
    const auto joint = static_cast<Eigen::Index>(protocol::Motor::clamp1);
    return std::clamp(-m.a_clamp * x + m.b_clamp, m.lower[joint], m.upper[joint]);
  }

  static constexpr int clamp1 = static_cast<int>(protocol::Motor::clamp1);  //!< pressing motor

 private:
  static transport::FaultRates loss_rates(double loss) noexcept {
    transport::FaultRates rates;
    rates.drop_send = loss;
    return rates;
  }

  static Rig::Config rig_config(const ClosedLoopConfig& c) {
    auto rig = endowrist_2016_rig<4>(Environment::free_space);
    auto& contact = rig.joints[clamp1].contact;
    contact.contact_position = c.contact_position;
    contact.direction = 1;
    if (c.contact == ContactKind::stiff_stop) {
      contact.environment = Environment::load_cell;
      if (c.stiffness > 0.0) contact.load_cell_stiffness = c.stiffness;
    } else {
      contact.environment = Environment::tissue;
      if (c.stiffness > 0.0) contact.tissue_stiffness = c.stiffness;
    }
    return rig;
  }

  static estimation::ForceEstimatorSettings<double> stiction_settings(const Rig::Config& rig) {
    estimation::ForceEstimatorSettings<double> s;
    stiction_memory_settings(rig, s);
    return s;
  }

  static Mapper::Config mapping(const ClosedLoopConfig& c) {
    Mapper::Config m;
    m.force_scale[0] = 2.0 * c.force_gain;
    m.channel_limit = Eigen::Vector3d::Constant(c.force_limit);
    m.force_limit = c.force_limit;
    return m;
  }

  static teleop::TeleopLoopConfig loop_config(const ClosedLoopConfig& c) {
    teleop::TeleopLoopConfig loop = c.loop;
    loop.passivity = c.passivity;
    // Clamp joint forces the mapping renders unclipped: |f| / 2 x 2 gain <= limit (eq. 5.8).
    for (const int j : {clamp1, clamp1 + 1}) {
      if (c.force_gain > 0.0) {
        loop.passivity.force_limit[j] =
            std::min(loop.passivity.force_limit[j], c.force_limit / c.force_gain);
      }
    }
    if (loop.period.count() > 0) {  // the robot port is booked one round trip late
      loop.passivity.round_trip_ticks =
          static_cast<int>(std::min<std::int64_t>((c.round_trip + loop.period / 2) / loop.period,
                                                  teleop::PassivityConfig::max_round_trip_ticks));
    }
    return loop;
  }

  // The press: from the rest pose straight in along -x (closing the clamps, eq. 5.9) to
  // press_depth beyond the radius where clamp 1 touches.
  static PressScript press_script(const ClosedLoopConfig& c) {
    const kinematics::CylindricalMapperConfig<double> mapping{};
    PressScript s;
    s.start = kinematics::rest_position<double>(mapping);
    const double touch_radius = (mapping.b_clamp - c.contact_position) / mapping.a_clamp;
    s.travel = Eigen::Vector3d(touch_radius - c.press_depth - s.start.x(), 0.0, 0.0);
    s.approach_start = c.approach_start;
    s.approach_time = c.approach_time;
    return s;
  }

  [[nodiscard]] double desired_clamp1() const noexcept { return clamp1_at(device_.position().x()); }

  // Delivers everything due up to `until`, in time order, moving the clock; with
  // `stop_on_arrival` returns at the first state that reaches the PC.
  void run_until(std::chrono::nanoseconds until, bool stop_on_arrival) noexcept {
    std::array<std::byte, 64> scratch{};
    for (;;) {
      std::chrono::nanoseconds due_f{0}, due_b{0};
      const bool has_f = forward_.next_due(due_f);
      const bool has_b = backward_.next_due(due_b);
      std::chrono::nanoseconds next = until;
      if (has_f) next = std::min(next, due_f);
      if (has_b) next = std::min(next, due_b);
      if ((!has_f || due_f > until) && (!has_b || due_b > until)) break;
      clock_.sleep_until(next);
      const auto now = clock_.now();
      std::size_t size = 0;
      Tag tag;
      while (forward_.pop_due(now, scratch, size, tag)) {
        to_sbrio_.push(std::span<const std::byte>(scratch.data(), size));
        (void)emulator_.poll(std::chrono::nanoseconds(0));  // may answer at once (no delay)
      }
      bool arrived = false;
      while (backward_.pop_due(now, scratch, size, tag)) {
        to_pc_.push(std::span<const std::byte>(scratch.data(), size));
        newest_force_ = tag;
        arrived = true;
      }
      if (arrived && stop_on_arrival) return;
    }
    clock_.sleep_until(until);
  }

  ClosedLoopConfig config_;
  ManualClock clock_{std::chrono::seconds(1)};
  Rig rig_;
  Line forward_;
  Line backward_;
  Queue to_sbrio_;
  Queue to_pc_;
  Queue unused_;
  PcEnd pc_end_;
  SbrioEnd sbrio_end_;
  PcTransport pc_transport_;
  SbrioTransport sbrio_transport_;
  Emulator emulator_;
  Device device_;
  estimation::MotorVector newest_force_ = estimation::MotorVector::Zero();
  estimation::ForceEstimatorSettings<double> stiction_;  // the instrument's stiction memory
  LoopForceEstimator sensor_;
  Mapper mapper_;
  Loop loop_;
  std::chrono::nanoseconds start_;
};

//! Analyses a press-and-hold run of `loop` (its samples, in order, from its start): contact onset,
//! first force peak, the oscillation 1 s after it and at the end, energy, limits, drift and the
//! stiffness felt at the stylus against the true one. Offline (allocates nothing, throws nothing).
[[nodiscard]] inline PressReport analyze_press(const ClosedLoop& loop,
                                               const std::vector<ClosedLoopSample>& samples) {
  PressReport r;
  if (samples.empty()) return r;
  const auto& cfg = loop.config();
  std::size_t onset = samples.size();
  const bool directional = cfg.passivity.mode == teleop::PassivityMode::tdpa &&
                           cfg.passivity.observer == teleop::PassivityObserver::per_direction;
  for (std::size_t i = 0; i < samples.size(); ++i) {
    const auto& p = samples[i].passivity;
    r.min_energy = std::min(
        r.min_energy, directional ? std::min(p.energy_to_robot, p.energy_to_operator) : p.energy);
    r.max_force = std::max(r.max_force, samples[i].commanded_force);
    if (onset == samples.size() && samples[i].contact_force > 0.05) onset = i;
  }
  if (onset == samples.size()) return r;
  r.contact = true;
  r.onset = samples[onset].time;
  std::size_t limited = 0;
  for (std::size_t i = onset; i < samples.size(); ++i) {
    if (samples[i].force_limited) ++limited;
    if (samples[i].time <= r.onset + 1.0 && std::fabs(samples[i].stylus_force) > r.first_peak) {
      r.first_peak = std::fabs(samples[i].stylus_force);
      r.peak_time = samples[i].time;
    }
  }
  r.saturated = static_cast<double>(limited) / static_cast<double>(samples.size() - onset);
  auto half_range = [&](double from, double to) {
    double lo = std::numeric_limits<double>::infinity(), hi = -lo;
    for (const auto& s : samples) {
      if (s.time < from || s.time > to) continue;
      lo = std::min(lo, s.stylus_force);
      hi = std::max(hi, s.stylus_force);
    }
    return hi >= lo ? (hi - lo) / 2 : 0.0;
  };
  r.decay_amplitude = half_range(r.peak_time + 1.0, r.peak_time + 1.5);
  const double end = samples.back().time;
  r.late_amplitude = half_range(end - 1.0, end);
  double force = 0.0, desired = 0.0, robot = 0.0, contact = 0.0, true_force = 0.0;
  int n = 0;
  for (const auto& s : samples) {
    if (s.time < end - 1.0) continue;
    force += s.stylus_force;
    desired += s.desired;
    robot += s.robot;
    contact += s.contact_force;
    true_force += s.true_stylus_force;
    ++n;
  }
  force /= n;
  desired /= n;
  robot /= n;
  contact /= n;
  r.hold_force = force;
  r.true_hold_force = true_force / n;
  r.drift = std::fabs(samples.back().desired - samples.back().setpoint);
  const double a = loop.mapper().config().a_clamp;  // rad of clamp 1 per m of stylus radius
  const double q = cfg.contact_position;
  if (desired - q > 1e-6) r.felt_stiffness = force * a / (desired - q);
  if (robot - q > 1e-6) r.true_stiffness = cfg.force_gain * contact * a / (robot - q);
  return r;
}

}  // namespace endohaptics::sim
