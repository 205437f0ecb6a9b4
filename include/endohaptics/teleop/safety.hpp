//! @file
//! Safety for the teleoperation loop: the link watchdog (worksheet 3.3.1: more than 10
//! consecutive receive deadlines missed = link lost), the safe-state policy, the force ramp after
//! recovery, and the setpoint rate limiter. Units: rad, rad/s, N, s. See docs/architecture.md.
#pragma once

#include <Eigen/Core>
#include <array>
#include <chrono>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <limits>
#include <string>
#include <string_view>
#include <utility>

#include "endohaptics/core/error.hpp"
#include "endohaptics/core/parameter.hpp"
#include "endohaptics/protocol/motor_order.hpp"
#include "endohaptics/teleop/state_plausibility.hpp"

namespace endohaptics::teleop {

//! What the robot does while the link is lost. The stylus force is zero in every case.
enum class SafeStatePolicy : std::uint8_t {
  hold_position,   //!< keep sending the last setpoint, motors enabled: the tool freezes
  disable_motors,  //!< send enable mask 0: the sbRIO releases the motors
  zero_force,      //!< keep following the operator, only the force feedback stops
};

//! The policy's name for logs ("hold-position", "disable-motors", "zero-force").
[[nodiscard]] constexpr std::string_view to_string(SafeStatePolicy p) noexcept {
  switch (p) {
    case SafeStatePolicy::hold_position:
      return "hold-position";
    case SafeStatePolicy::disable_motors:
      return "disable-motors";
    case SafeStatePolicy::zero_force:
      return "zero-force";
  }
  return "unknown policy";
}

//! The policies by their configuration names ("hold_position", "disable_motors", "zero_force").
[[nodiscard]] constexpr std::array<std::pair<std::string_view, SafeStatePolicy>, 3> enumerators(
    SafeStatePolicy) noexcept {
  return {{{"hold_position", SafeStatePolicy::hold_position},
           {"disable_motors", SafeStatePolicy::disable_motors},
           {"zero_force", SafeStatePolicy::zero_force}}};
}

//! Link state as the watchdog sees it.
enum class LinkState : std::uint8_t {
  waiting,     //!< no valid state packet yet: motors stay disabled, no force
  up,          //!< the last exchange succeeded
  degraded,    //!< 1..max consecutive misses: last estimate held, still "up" for the robot
  lost,        //!< more than max consecutive misses: safe state
  recovering,  //!< valid packets again after a loss: force ramps back in
};

//! Whether the link holds a valid state in `s`: up, degraded or recovering (not before the first
//! valid state, not once it is lost).
[[nodiscard]] constexpr bool holds_valid_state(LinkState s) noexcept {
  return s != LinkState::waiting && s != LinkState::lost;
}

//! The state's name for logs ("waiting", "up", "degraded", "lost", "recovering").
[[nodiscard]] constexpr std::string_view to_string(LinkState s) noexcept {
  switch (s) {
    case LinkState::waiting:
      return "waiting";
    case LinkState::up:
      return "up";
    case LinkState::degraded:
      return "degraded";
    case LinkState::lost:
      return "lost";
    case LinkState::recovering:
      return "recovering";
  }
  return "unknown";
}

//! The physical bounds SafetyConfig::validate enforces (the largest values it accepts).
struct SafetyBounds {
  static constexpr int max_consecutive_misses = 1000;  //!< see also TeleopLoopConfig's 0.5 s
  static constexpr double max_force_ramp_time = 10.0;  //!< s
  static constexpr double max_hold_time = 60.0;        //!< s, the longest bounded hold
  //! s: the longest a robot may take to report a motor active once enabled (a round trip of up
  //! to a few seconds on a delayed link included).
  static constexpr double max_activation_timeout = 10.0;
  //! rad/s at the gear output: what the motor can do at all (PlausibilityBounds::max_velocity).
  static constexpr double max_setpoint_rate = PlausibilityBounds::max_velocity;
  static constexpr double max_stylus_force = 3.3;  //!< N, the Geomagic Touch's peak force
  //! rad: a joint range lies inside [-joint_limit, joint_limit] (the EndoWrist's is +-1.028).
  static constexpr double joint_limit = 3.14159265358979323846;
};

//! One value per motor (motor order, as on the wire).
using JointVector = Eigen::Matrix<double, protocol::endowrist_motors, 1>;

//! Safety limits and link-loss behaviour of a TeleopLoop: the envelope every command stays in.
//! Units: s, rad, rad/s, N. Every field has a physical range (SafetyBounds, StatePlausibility).
struct SafetyConfig {
  int max_consecutive_misses = 10;  //!< link lost when misses exceed this (2016: "superior to 10")
  //! Robot behaviour while the link is lost. Default: release the motors (the sbRIO's own
  //! watchdog does the same); holding or following is an explicit choice, bounded in time by
  //! max_hold_time.
  SafeStatePolicy policy = SafeStatePolicy::disable_motors;
  //! s: with hold_position or zero_force, the motors are released (enable mask 0) once the link
  //! has been lost this long: a lost link never keeps the tool powered indefinitely.
  double max_hold_time = 2.0;
  double force_ramp_time = 0.5;  //!< s, force scale 0 -> 1 after recovery (and at start)
  //! rad/s per joint (motor side); the tool cannot go faster
  double max_setpoint_rate = protocol::endowrist_max_joint_rate;
  double max_stylus_force = 3.0;    //!< N, last guard before the device (Touch peak: 3.3 N)
  std::uint8_t enable_mask = 0x0F;  //!< motors to enable while the link is usable
  //! s: a motor enabled in every setpoint sent for longer than this must be reported active. A
  //! state that shows it inactive was not obeyed (the robot ignores or refuses the setpoints):
  //! a miss, never "link up". Raise it above the link's round trip on a delayed link.
  double activation_timeout = 0.05;
  //! rad, motor order: every setpoint the loop sends lies in [joint_lower, joint_upper],
  //! whatever the stylus, the mapper or the robot's reported state say. Default: the +-1.028 rad
  //! of the 2016 tuning logs (CylindricalMapperConfig's range).
  JointVector joint_lower = JointVector::Constant(-protocol::endowrist_joint_range);
  //! rad, motor order
  JointVector joint_upper = JointVector::Constant(protocol::endowrist_joint_range);
  StatePlausibility plausibility{};  //!< what a reported state may say (else: a fault)

  //! `position` (rad, motor order) limited to [joint_lower, joint_upper], joint by joint.
  [[nodiscard]] JointVector clamp_to_range(const JointVector& position) const noexcept {
    return position.cwiseMax(joint_lower).cwiseMin(joint_upper);
  }

  //! Every field but `plausibility` (its own list) by its configuration name, with its bound
  //! (core/parameter.hpp): the one list validate() and the bridge configuration use.
  template <typename Self, typename Visitor>
  static void for_each_field(Self& p, Visitor&& v) {
    using B = SafetyBounds;
    const Bound joint =
        Bound::in(-B::joint_limit, B::joint_limit, "rad").described("in [-pi, pi] rad");
    v("max_consecutive_misses", p.max_consecutive_misses, Bound::in(0, B::max_consecutive_misses));
    v("policy", p.policy, Bound{});
    v("max_hold_time", p.max_hold_time, Bound::above(0, B::max_hold_time, "s"));
    v("force_ramp_time", p.force_ramp_time, Bound::in(0, B::max_force_ramp_time, "s"));
    v("max_setpoint_rate", p.max_setpoint_rate, Bound::above(0, B::max_setpoint_rate, "rad/s"));
    v("max_stylus_force", p.max_stylus_force,
      Bound::in(0, B::max_stylus_force, "N").described("in [0, 3.3] N (the Touch's peak)"));
    v("enable_mask", p.enable_mask, Bound::in(0, 255));
    v("activation_timeout", p.activation_timeout, Bound::above(0, B::max_activation_timeout, "s"));
    v("joint_lower", p.joint_lower, joint);
    v("joint_upper", p.joint_upper, joint);
  }

  //! Throws ParameterError naming the field, the value and the allowed range. `motors` (1..8):
  //! how many the link carries; the enable mask may only name those (bits 0..motors-1).
  void validate(int motors = protocol::endowrist_motors) const {
    auto hex = [](unsigned value) {
      char text[16];
      std::snprintf(text, sizeof text, "0x%02X", value);
      return std::string(text);
    };
    const ParameterChecker check{"SafetyConfig"};
    check.require(motors >= 1 && motors <= 8, "motors", motors, "1..8 (one mask byte)");
    for_each_field(*this, check);
    const unsigned allowed = (1u << static_cast<unsigned>(motors)) - 1u;
    check.require_text((enable_mask & ~allowed) == 0u, "enable_mask", hex(enable_mask),
                       "<= " + hex(allowed) + " (bits 0.." + std::to_string(motors - 1) + ": " +
                           std::to_string(motors) + " motors)");
    for (int m = 0; m < protocol::endowrist_motors; ++m) {
      check.require(joint_lower[m] < joint_upper[m], "joint_upper[" + std::to_string(m) + "]",
                    joint_upper[m], "above joint_lower[" + std::to_string(m) + "]");
    }
    plausibility.validate();
  }
};

//! Consecutive-miss counter with link-lost and recovery events. `update` once per exchange.
class Watchdog {
 public:
  //! Link lost once more than `max_consecutive_misses` exchanges in a row have missed.
  explicit Watchdog(int max_consecutive_misses = 10) noexcept : max_(max_consecutive_misses) {}

  //! `received`: a valid state packet arrived this tick. `ramp_done`: the force ramp finished.
  LinkState update(bool received, bool ramp_done) noexcept {
    if (received) {
      misses_ = 0;
      if (state_ == LinkState::lost) {
        ++recoveries_;
        state_ = LinkState::recovering;
      } else if (state_ == LinkState::waiting) {
        state_ = LinkState::recovering;  // first contact: ramp the force in too
      } else if (state_ == LinkState::recovering) {
        if (ramp_done) state_ = LinkState::up;
      } else {
        state_ = LinkState::up;
      }
      return state_;
    }
    if (misses_ < std::numeric_limits<int>::max()) ++misses_;  // a dead peer for days
    ++total_misses_;
    if (state_ == LinkState::waiting || state_ == LinkState::lost) return state_;
    if (misses_ > max_) {
      state_ = LinkState::lost;
      ++losses_;
    } else if (state_ == LinkState::up) {
      state_ = LinkState::degraded;
    }
    return state_;
  }

  //! An implausible state arrived (StateFault): a miss, and the link is lost at once unless it
  //! is still waiting for its first valid state (then nothing was ever enabled).
  LinkState fault() noexcept {
    if (misses_ < std::numeric_limits<int>::max()) ++misses_;
    ++total_misses_;
    if (holds_valid_state(state_)) {
      state_ = LinkState::lost;
      ++losses_;
    }
    return state_;
  }

  //! Current link state (waiting until the first valid packet).
  [[nodiscard]] LinkState state() const noexcept { return state_; }
  //! Misses since the last valid packet.
  [[nodiscard]] int consecutive_misses() const noexcept { return misses_; }
  //! Misses since construction or reset().
  [[nodiscard]] std::uint64_t total_misses() const noexcept { return total_misses_; }
  //! Transitions into LinkState::lost since construction or reset().
  [[nodiscard]] std::uint64_t link_losses() const noexcept { return losses_; }
  //! Valid packets received after a loss (lost -> recovering) since construction or reset().
  [[nodiscard]] std::uint64_t recoveries() const noexcept { return recoveries_; }
  //! True while the robot must be in its safe state.
  [[nodiscard]] bool safe_state() const noexcept { return state_ == LinkState::lost; }
  //! Back to LinkState::waiting with every counter zeroed; keeps the miss limit.
  void reset() noexcept { *this = Watchdog(max_); }

 private:
  int max_;
  int misses_ = 0;
  LinkState state_ = LinkState::waiting;
  std::uint64_t total_misses_ = 0;
  std::uint64_t losses_ = 0;
  std::uint64_t recoveries_ = 0;
};

//! Linear force scale 0 -> 1 over `ramp_time` seconds; restarted on every recovery.
class ForceRamp {
 public:
  //! `ramp_time`: s from scale 0 to 1; <= 0 jumps straight to 1 on the first advance().
  explicit ForceRamp(double ramp_time) noexcept : ramp_time_(ramp_time) {}
  //! Starts the ramp again from scale 0 (after a recovery or first contact).
  void restart() noexcept { scale_ = 0.0; }
  //! Sets the scale to 0 while no force is rendered; the next advance() ramps up from there.
  void hold_at_zero() noexcept { scale_ = 0.0; }
  //! Advances by dt seconds; returns the scale to apply this tick.
  double advance(double dt) noexcept {
    scale_ = ramp_time_ > 0.0 ? std::fmin(1.0, scale_ + dt / ramp_time_) : 1.0;
    return scale_;
  }
  //! Current scale, 0..1.
  [[nodiscard]] double scale() const noexcept { return scale_; }
  //! True once the scale has reached 1.
  [[nodiscard]] bool done() const noexcept { return scale_ >= 1.0; }

 private:
  double ramp_time_;
  double scale_ = 0.0;
};

//! Limits how fast each setpoint may move: |out - previous| <= max_rate * dt per joint.
template <int N>
class SetpointRateLimiter {
 public:
  using Vector = Eigen::Matrix<double, N, 1>;  //!< one setpoint per joint, rad
  //! `max_rate`: rad/s per joint (+inf: no limit).
  explicit SetpointRateLimiter(double max_rate) noexcept : max_rate_(max_rate) {}

  //! Starts from a known position (the robot's measured one), so the first step is bounded too.
  void initialize(const Vector& from) noexcept {
    previous_ = from;
    initialized_ = true;
  }
  //! True once initialize() or shape() has set a starting position.
  [[nodiscard]] bool initialized() const noexcept { return initialized_; }

  //! Moves the previous output towards `desired`; returns true when it had to limit.
  bool shape(const Vector& desired, double dt, Vector& out) noexcept {
    if (!initialized_) initialize(desired);
    const double step = max_rate_ * dt;
    const Vector delta = (desired - previous_).cwiseMax(-step).cwiseMin(step);
    const bool limited = ((desired - previous_) - delta).cwiseAbs().maxCoeff() > 0.0;
    previous_ += delta;
    out = previous_;
    return limited;
  }
  //! The last output (rad), or the initial position; zero before initialization.
  [[nodiscard]] const Vector& previous() const noexcept { return previous_; }

 private:
  double max_rate_;
  Vector previous_ = Vector::Zero();
  bool initialized_ = false;
};

}  // namespace endohaptics::teleop
