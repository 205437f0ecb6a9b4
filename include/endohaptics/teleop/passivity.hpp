//! @file
//! Time-domain passivity (TDPA) for the TeleopLoop's channel, per joint: a passivity observer
//! (PO) of the channel's energy and a passivity controller (PC) on each port (Hannaford & Ryu
//! 2002; Ryu, Kwon & Hannaford 2004). Operator port: impedance-type PC, variable damping on the
//! rendered force. Robot port: observed at the setpoint (energy reference of a position-force
//! architecture, Ryu, Artigas & Preusche 2010), aligned by the round trip as the network TDPA
//! sees the other side's energy late (Artigas et al. 2011; Coelho et al. 2019); its PC shortens
//! setpoint steps, and the loop's rate limiter gives the held-back position back (drift
//! compensation). Energies in J at the tool (N x lever m/rad x rad). See docs/passivity.md.
#pragma once

#include <Eigen/Core>
#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <limits>
#include <string>
#include <string_view>
#include <utility>

#include "endohaptics/core/error.hpp"
#include "endohaptics/core/parameter.hpp"
#include "endohaptics/estimation/joint_force_estimator.hpp"

namespace endohaptics::teleop {

//! What keeps the force-feedback channel stable under delay and loss.
enum class PassivityMode : std::uint8_t {
  off = 0,  //!< nothing: the estimate is rendered and the setpoint sent as they are
  observe,  //!< the observer only (energy figures; force and setpoint unchanged)
  tdpa,     //!< time-domain passivity: observer and controllers on both ports
  // room for wave_variables (Niemeyer & Slotine): the same hooks with a channel transform
};

//! The mode's name ("off", "observe", "tdpa").
[[nodiscard]] constexpr std::string_view to_string(PassivityMode m) noexcept {
  switch (m) {
    case PassivityMode::off:
      return "off";
    case PassivityMode::observe:
      return "observe";
    case PassivityMode::tdpa:
      return "tdpa";
  }
  return "unknown";
}

//! How the observer splits the channel's energy between the two controllers.
enum class PassivityObserver : std::uint8_t {
  //! One observer per joint (both ports summed) drives both controllers.
  combined = 0,
  //! Per direction (the two-port network TDPA of Artigas et al. 2011): the robot-side controller
  //! answers for operator -> robot (what the operator put in, booked with the force before the
  //! operator-side controller, minus what the setpoint put into the environment), the
  //! operator-side one for robot -> operator (what the robot gave back minus what the hand got):
  //! neither controller's action feeds the other's observer, nor its own.
  per_direction,
};

//! The observers by their configuration names ("combined", "per_direction").
[[nodiscard]] constexpr std::array<std::pair<std::string_view, PassivityObserver>, 2> enumerators(
    PassivityObserver) noexcept {
  return {{{"combined", PassivityObserver::combined},
           {"per_direction", PassivityObserver::per_direction}}};
}

//! Settings of the passivity layer.
struct PassivityConfig {
  using Vector = estimation::MotorVector;  //!< one value per motor (motor order)
  //! Setpoint history kept to align the robot port with the round trip (ticks).
  static constexpr int max_round_trip_ticks = 1023;
  //! N: the largest estimate_tolerance and robot_cost_tolerance (above the estimator's output
  //! limit of 9.81 N, ForceEstimatorSettings::output_limit).
  static constexpr double max_tolerance = 10.0;

  PassivityMode mode = PassivityMode::off;  //!< off, observe or tdpa
  //! Ticks between sending a setpoint and receiving the state measured while the robot followed
  //! it (the round trip in loop periods, 0..max_round_trip_ticks): the robot port's setpoint
  //! motion is booked this much later, when its force is known at the operator's side.
  int round_trip_ticks = 0;
  //! m/rad per motor: tool displacement per joint rad, so that N x lever x rad is J at the tool.
  //! Defaults: the lever arms of sim::endowrist_2016_rig (roll, pitch 0.18 m; clamps 0.32 m).
  Vector lever = (Vector() << 0.18, 0.18, 0.32, 0.32).finished();
  //! m at the tool: a port that moved less than this in a tick carries no power (no division).
  double min_motion = 1e-9;
  //! N per motor: the largest joint force the mapping and the device render without a limit
  //! scaling it; the layer renders at most this, so the force it books is the force felt. Set it
  //! from the mapper's and the device's limits (default: no limit).
  Vector force_limit = Vector::Constant(std::numeric_limits<double>::infinity());
  //! J per joint: the energy the operator-side PC lets the observer borrow, scaling the force
  //! down linearly as the observer goes from 0 to -energy_reserve (no force beyond). A finite
  //! initial storage: the channel stays passive with this bound.
  double energy_reserve = 0.01;
  //! 1/s: the operator-side force scale returns towards 1 at most this fast once energy allows.
  double gain_recovery_rate = 0.2;
  //! Which observer drives the controllers (combined keeps the layer as it was).
  PassivityObserver observer = PassivityObserver::combined;
  //! N per motor, >= 0: the bound of the force estimate's error (a sensorless estimate is not
  //! zero in free motion). Both ports book the force shrunk towards zero by this much (a dead
  //! band), and the operator-side controller renders that shrunk force: a force within the band
  //! is neither felt nor booked, so an estimate error within it cannot drain the observer, and
  //! what the operator feels is what the observer booked. 0: the force as it is.
  Vector estimate_tolerance = Vector::Zero();
  //! True: energy comes back at the robot port only as far as both the setpoint and the robot's
  //! reported motion show it (right for a force sensor: a robot held at a stop by its servo
  //! returns nothing however far the setpoint retreats, while the sensor still reads the stop).
  //! False: as far as the setpoint shows it; right for a sensorless estimate, which reads what
  //! the servo pushes (its current): with the robot stuck (a stop, stiction) that force follows
  //! the setpoint's distance from the robot, a spring the setpoint stores energy in and gets back.
  bool robot_return_needs_motion = true;
  //! N per motor, >= 0: the robot-side PC charges a setpoint step only against the force beyond
  //! this band (on top of estimate_tolerance). A sensorless estimate's free-motion error bound:
  //! a step against a force the estimate cannot tell from zero is not held back. Without it a
  //! standing deficit (the robot-side PC never reverses a step, so nothing repays it) stops
  //! every step against any force however small, and the setpoint stays behind the hand for
  //! good. The observer still books the force as it is. 0: every step is charged.
  Vector robot_cost_tolerance = Vector::Zero();
  //! False: the operator-side force scale follows the deficit (1 + E / energy_reserve) at every
  //! tick. True: only on ticks where the operator port gives the hand energy (the force along
  //! the hand's motion), the condition of the impedance-type PC of Ryu, Kwon & Hannaford 2004;
  //! on the others (a still hand, a hand pressing into the force: no work done on it) the scale
  //! comes back at gain_recovery_rate, so a hold after an impact is felt again.
  bool recover_while_absorbing = false;

  //! The fields a configuration sets, by their configuration names, with their bounds
  //! (core/parameter.hpp): the one list validate() and the bridge configuration's "passivity"
  //! section use. mode, round_trip_ticks and force_limit are the program's (--passivity,
  //! --passivity-round-trip, the mapping's limits) and are checked apart.
  template <typename Self, typename Visitor>
  static void for_each_field(Self& p, Visitor&& v) {
    constexpr double inf = std::numeric_limits<double>::infinity();
    v("observer", p.observer, Bound{});
    v("energy_reserve", p.energy_reserve, Bound::above(0, inf, "J"));
    v("gain_recovery_rate", p.gain_recovery_rate, Bound::above(0, inf, "1/s"));
    // A tolerance beyond max_tolerance (the estimator's output limit, 9.81 N) would switch the
    // feedback or the robot-side controller off for good: a typo, refused.
    v("estimate_tolerance", p.estimate_tolerance, Bound::in(0, max_tolerance, "N"));
    v("robot_cost_tolerance", p.robot_cost_tolerance, Bound::in(0, max_tolerance, "N"));
    v("robot_return_needs_motion", p.robot_return_needs_motion, Bound{});
    v("recover_while_absorbing", p.recover_while_absorbing, Bound{});
    v("lever", p.lever, Bound::above(0, inf, "m/rad"));
    v("min_motion", p.min_motion, Bound::above(0, inf, "m"));
  }

  //! Throws Error naming the field and value (ParameterError for the fields of for_each_field).
  void validate() const {
    for_each_field(*this, ParameterChecker{"PassivityConfig"});
    if (mode != PassivityMode::off && mode != PassivityMode::observe &&
        mode != PassivityMode::tdpa) {
      ENDOHAPTICS_THROW(Error("PassivityConfig: mode must be off, observe or tdpa, got " +
                              std::to_string(static_cast<int>(mode))));
    }
    if (round_trip_ticks < 0 || round_trip_ticks > max_round_trip_ticks) {
      ENDOHAPTICS_THROW(Error("PassivityConfig: round_trip_ticks must be in [0, " +
                              std::to_string(max_round_trip_ticks) + "], got " +
                              std::to_string(round_trip_ticks)));
    }
    for (int j = 0; j < force_limit.size(); ++j) {
      if (std::isnan(force_limit[j]) || !(force_limit[j] > 0.0)) {
        ENDOHAPTICS_THROW(Error("PassivityConfig: force_limit[" + std::to_string(j) +
                                "] must be > 0 N, got " +
                                endohaptics::detail::format_number(force_limit[j])));
      }
    }
  }
};

//! The passivity figures of one tick (all zero with PassivityMode::off). Sums over the joints.
struct PassivityFigures {
  double energy = 0.0;               //!< J, the observer: the channel's energy, >= 0 if passive
  double energy_operator = 0.0;      //!< J, put in at the operator port (in - out) so far
  double energy_robot = 0.0;         //!< J, put in at the robot port (in - out) so far
  double dissipated_operator = 0.0;  //!< J, removed by the operator-side PC so far
  double dissipated_robot = 0.0;     //!< J, removed by the robot-side PC so far
  double damping = 0.0;     //!< N s/m at the tool, the operator-side PC as a damper (largest)
  double force_gain = 1.0;  //!< the operator-side PC's force scale now (smallest joint), 0..1
  double drift = 0.0;       //!< rad, largest |desired - sent| setpoint difference (held back)
  //! J, operator -> robot: what the operator put in (force before the operator-side PC) minus
  //! what the setpoint put into the environment (PassivityObserver::per_direction's robot side)
  double energy_to_robot = 0.0;
  //! J, robot -> operator: what the environment gave back minus what the hand got
  //! (PassivityObserver::per_direction's operator side)
  double energy_to_operator = 0.0;
  bool operator_active = false;  //!< the operator-side PC changed the force this tick
  bool robot_active = false;     //!< the robot-side PC changed the setpoint this tick
};

//! TDPA state of the four joints: fixed size, every member noexcept and allocation-free. The
//! TeleopLoop calls, per tick: `track_desired` (operator port: motion, energy of the force last
//! rendered), `shape_setpoint` (robot-side PC) and `commit` (what was sent), then `shape_force`
//! (robot port booked one round trip late; operator-side PC) or `render_nothing`. With
//! PassivityMode::off every call returns at once, passing force and setpoint through.
class TimeDomainPassivity {
 public:
  using Vector = estimation::MotorVector;  //!< motor order

  //! Throws Error on an invalid configuration.
  explicit TimeDomainPassivity(const PassivityConfig& config = {})
      : config_((config.validate(), config)),
        inverse_reserve_(1.0 / config.energy_reserve),
        per_direction_(config.observer == PassivityObserver::per_direction) {
    history_.fill(Vector::Zero());
  }

  //! The validated configuration.
  [[nodiscard]] const PassivityConfig& config() const noexcept { return config_; }
  //! True when the observer runs (observe, tdpa).
  [[nodiscard]] bool enabled() const noexcept { return config_.mode != PassivityMode::off; }
  //! True when the controllers act too (tdpa).
  [[nodiscard]] bool controlling() const noexcept { return config_.mode == PassivityMode::tdpa; }

  //! Starts a new contact (first state, recovery): energies zero, the setpoint history filled
  //! with `sent` (rad, the setpoint the robot follows now). Dissipation totals are kept.
  void reset(const Vector& sent) noexcept {
    if (!enabled()) return;
    in_operator_.setZero();
    out_operator_.setZero();
    in_network_.setZero();
    network_.setZero();
    in_robot_.setZero();
    out_robot_.setZero();
    in_setpoint_.setZero();
    in_measured_.setZero();
    rendered_.setZero();
    gain_.setOnes();
    gain_min_ = 1.0;
    estimate_.setZero();
    history_.fill(sent);
    sent_ = sent;
    have_robot_ = false;  // no motion booked across the outage against the force before it
    started_ = true;
  }

  //! Operator port, once per tick: the desired (range-clamped) setpoint `desired` (rad); books
  //! the energy the force rendered last tick did over this motion.
  void track_desired(const Vector& desired) noexcept {
    if (!enabled()) return;  // off: the layer costs the loop one branch per call
    motion_ = have_desired_ ? Vector(desired - desired_) : Vector(Vector::Zero());
    desired_ = desired;
    have_desired_ = true;
    const Vector step = motion_.cwiseProduct(config_.lever);
    const Vector power = rendered_.cwiseProduct(step);
    out_operator_ += power.cwiseMax(0.0);  // > 0: the channel worked on the hand
    in_operator_ += (-power).cwiseMax(0.0);
    // The same motion against the force before the operator-side PC: what the operator put in
    // as far as the robot side is concerned (the PC's scaling is not the robot's to answer for).
    in_network_ += (-network_.cwiseProduct(step)).cwiseMax(0.0);
  }

  //! Robot-side PC (admittance type): while the observer shows a deficit, shortens the step from
  //! `from` (rad, where the setpoint shaping started: TeleopLoop passes its rate limiter's origin,
  //! so the result, a point between `from` and `candidate`, keeps the rate limit) to `candidate`
  //! that would push against the newest force `force` (N), by at most the deficit (energy
  //! reference: the step's energy against that force); it never reverses a step. Writes the
  //! setpoint to send; returns true when it changed it.
  bool shape_setpoint(const Vector& candidate, const Vector& from, const Vector& force,
                      Vector& out) noexcept {
    out = candidate;
    if (!controlling() || !started_) return false;
    bool changed = false;
    const Vector booked =
        tolerated(force, config_.estimate_tolerance + config_.robot_cost_tolerance);
    for (int j = 0; j < Vector::SizeAtCompileTime; ++j) {
      const double deficit = per_direction_ ? -energy_to_robot(j) : -energy(j);
      const double step = (candidate[j] - from[j]) * config_.lever[j];  // m at the tool
      const double cost = -booked[j] * step;  // J this step puts into the environment
      if (deficit > 0.0 && cost > 0.0) {
        const double keep = std::clamp((cost - deficit) / cost, 0.0, 1.0);
        out[j] = from[j] + keep * (candidate[j] - from[j]);
        dissipated_robot_ += (1.0 - keep) * cost;
        changed = true;
      }
    }
    return changed;
  }
  //! As above, the step from the last setpoint committed.
  bool shape_setpoint(const Vector& candidate, const Vector& force, Vector& out) noexcept {
    return shape_setpoint(candidate, sent_, force, out);
  }

  //! Records the setpoint actually sent this tick (rad) in the history (every tick).
  void commit(const Vector& sent) noexcept {
    if (!enabled()) return;
    sent_ = sent;
    head_ = head_ + 1 == history_.size() ? 0 : head_ + 1;  // no division on the tick
    history_[head_] = sent;
  }

  //! Robot-port PO and operator-side PC (impedance type), on a tick that renders force: books the
  //! robot port's energy (the setpoint step of one round trip ago against `force`, the newest
  //! estimate, N), then, while the observer shows a deficit, adds the damping that removes it
  //! from this tick's output to the hand; it never reverses the force. Writes the force to
  //! render; `dt` s. Returns true when it changed the force.
  bool shape_force(const Vector& estimate, double dt, Vector& out) noexcept {
    out = estimate;
    damping_ = 0.0;
    if (!enabled()) return false;
    // What the mapping and the device render: beyond it the booked power would not be real;
    // within the estimate's error bound nothing is booked (nor, with the PC, rendered).
    const Vector force =
        tolerated(estimate).cwiseMax(-config_.force_limit).cwiseMin(config_.force_limit);
    if (started_) {
      const std::size_t n = history_.size();
      const auto back = static_cast<std::size_t>(config_.round_trip_ticks);  // < n - 1
      const std::size_t then = head_ >= back ? head_ - back : head_ + n - back;
      const std::size_t before = then == 0 ? n - 1 : then - 1;
      const Vector step = (history_[then] - history_[before]).cwiseProduct(config_.lever);
      // The force of the previous tick, as the operator port books the force rendered last tick:
      // with no delay and no PC both ports then carry the same power (the observer stays at 0).
      const Vector power = -estimate_.cwiseProduct(step);  // > 0: work on the environment
      out_robot_ += power.cwiseMax(0.0);
      in_setpoint_ += (-power).cwiseMax(0.0);
      // Energy comes back only as far as both the setpoint and the robot's reported motion show
      // it: a robot held at the contact by its servo returns nothing however far the setpoint
      // retreats.
      in_robot_ =
          config_.robot_return_needs_motion ? in_setpoint_.cwiseMin(in_measured_) : in_setpoint_;
    }
    estimate_ = force;
    bool changed = false;
    if (controlling()) {
      out = force;
      const Vector step = motion_.cwiseProduct(config_.lever);  // m at the tool, this tick
      double damping_force = 0.0, damping_step = 1.0;           // the largest damping as a ratio
      for (int j = 0; j < Vector::SizeAtCompileTime; ++j) {
        // The force is scaled down as the observer dips into the reserve (none left: no force),
        // and comes back at most gain_recovery_rate per s: a smooth variable damping rather than
        // a switch, which would kick a light stylus at 1 kHz.
        const double e = per_direction_ ? energy_to_operator(j) : energy(j);
        double g = gain_[j] + dt * config_.gain_recovery_rate;
        // Scaled to the deficit while the port gives the hand energy (or always, by default);
        // with recover_while_absorbing, a force that does no work on the hand (the hand still,
        // or pressing into it) comes back at the recovery rate whatever the deficit.
        if (!config_.recover_while_absorbing || force[j] * step[j] > 0.0) {
          g = std::min(g, std::clamp(1.0 + e * inverse_reserve_, 0.0, 1.0));
        }
        g = std::min(g, 1.0);
        gain_[j] = g;
        if (g < 1.0) {
          out[j] = g * force[j];
          const double cost = force[j] * step[j];
          if (cost > 0.0) dissipated_operator_ += (1.0 - g) * cost;
          // f_r = f - alpha v: the damper alpha = |taken| dt / |step| that takes the same force
          // away at this velocity (compared as ratios: one division per tick, not per joint).
          const double moved = std::fabs(step[j]);
          const double taken = std::fabs((1.0 - g) * force[j]) * dt;
          if (moved > config_.min_motion && taken * damping_step > damping_force * moved) {
            damping_force = taken;
            damping_step = moved;
          }
          changed = true;
        }
      }
      gain_min_ = gain_.minCoeff();
      damping_ = damping_force / damping_step;
    }
    rendered_ = controlling() ? out : force;
    network_ = force;
    return changed;
  }

  //! Robot-port PO on a fresh state: the robot's reported position (rad) and the force estimated
  //! from the same state (N); both left the robot together, so they need no alignment.
  void observe_robot(const Vector& position, const Vector& force) noexcept {
    if (!enabled()) return;
    if (started_ && have_robot_) {
      const Vector step = (position - robot_position_).cwiseProduct(config_.lever);
      const Vector power = -robot_force_.cwiseProduct(step);  // as the setpoint is booked
      in_measured_ += (-power).cwiseMax(0.0);  // the environment pushed the robot back
    }
    robot_position_ = position;
    robot_force_ = tolerated(force);
    have_robot_ = true;
  }

  //! A tick without force rendered (lost link, device fault): the operator port carries nothing.
  void render_nothing() noexcept {
    rendered_.setZero();
    network_.setZero();
    damping_ = 0.0;
  }

  //! The figures after this tick's calls.
  [[nodiscard]] PassivityFigures figures() const noexcept {
    PassivityFigures f;
    if (!enabled()) return f;
    f.energy_operator = (in_operator_ - out_operator_).sum();
    f.energy_robot = (in_robot_ - out_robot_).sum();
    f.energy = f.energy_operator + f.energy_robot;
    f.dissipated_operator = dissipated_operator_;
    f.dissipated_robot = dissipated_robot_;
    f.damping = damping_;
    f.force_gain = gain_min_;
    f.drift = have_desired_ && started_ ? (desired_ - sent_).cwiseAbs().maxCoeff() : 0.0;
    f.energy_to_robot = (in_network_ - out_robot_).sum();
    f.energy_to_operator = (in_robot_ - out_operator_).sum();
    return f;
  }
  //! J, the observer of joint `j`: what the operator and the robot port put into the channel.
  [[nodiscard]] double energy(int j) const noexcept {
    return in_operator_[j] - out_operator_[j] + in_robot_[j] - out_robot_[j];
  }
  //! J, joint `j` operator -> robot: in at the operator port (force before the operator-side PC)
  //! minus out at the robot port.
  [[nodiscard]] double energy_to_robot(int j) const noexcept {
    return in_network_[j] - out_robot_[j];
  }
  //! J, joint `j` robot -> operator: in at the robot port minus out to the hand.
  [[nodiscard]] double energy_to_operator(int j) const noexcept {
    return in_robot_[j] - out_operator_[j];
  }

 private:
  // The force shrunk towards zero by the estimate's error bound (PassivityConfig::
  // estimate_tolerance): f - clamp(f, -tol, tol).
  [[nodiscard]] Vector tolerated(const Vector& force) const noexcept {
    return tolerated(force, config_.estimate_tolerance);
  }
  // `force` shrunk towards zero by `band` per joint (0 within it).
  [[nodiscard]] static Vector tolerated(const Vector& force, const Vector& band) noexcept {
    return force - force.cwiseMax(-band).cwiseMin(band);
  }

  PassivityConfig config_;
  double inverse_reserve_;                // 1 / energy_reserve (no division per joint on the tick)
  bool per_direction_;                    // PassivityObserver::per_direction
  Vector in_network_ = Vector::Zero();    // J in at the operator port, force before the PC
  Vector network_ = Vector::Zero();       // N, the force last tick before the operator-side PC
  Vector in_operator_ = Vector::Zero();   // J the operator put into the channel
  Vector out_operator_ = Vector::Zero();  // J the channel put into the operator
  Vector in_robot_ = Vector::Zero();      // J the environment gave back at the setpoint
  Vector out_robot_ = Vector::Zero();     // J the setpoint put into the environment
  Vector in_setpoint_ = Vector::Zero();   // J returned at the setpoint (energy reference)
  Vector in_measured_ = Vector::Zero();   // J returned by the robot's reported motion
  Vector desired_ = Vector::Zero();
  Vector motion_ = Vector::Zero();  // rad, desired setpoint change this tick
  Vector sent_ = Vector::Zero();
  Vector rendered_ = Vector::Zero();  // N, the force last rendered (after the PC)
  Vector estimate_ = Vector::Zero();  // N, the estimate shape_force got last tick
  Vector gain_ = Vector::Ones();      // operator-side force scale per joint, 0..1
  double gain_min_ = 1.0;             // the PC reduced this joint's force; it is coming back
  std::array<Vector, PassivityConfig::max_round_trip_ticks + 2> history_{};  // sent setpoints
  std::size_t head_ = 0;
  Vector robot_position_ = Vector::Zero();
  Vector robot_force_ = Vector::Zero();
  bool have_robot_ = false;
  double dissipated_operator_ = 0.0;
  double dissipated_robot_ = 0.0;
  double damping_ = 0.0;
  bool have_desired_ = false;
  bool started_ = false;
};

}  // namespace endohaptics::teleop
