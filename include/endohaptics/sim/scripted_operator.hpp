//! @file
//! ScriptedOperator: a simulated operator holding the stylus (a teleop::HapticDevice). The hand
//! follows a grasp-and-release script in cylindrical coordinates (figure 5.14: the radius r
//! closes the clamps, eq. 5.9), and the stylus is where the arm of worksheet 5.1 (eq. 5.3,
//! table 5.1) puts it under the force the loop renders. Units: m, s, N; positions and forces in
//! CylindricalMapper's mapping frame (kinematics/cylindrical_mapper.hpp: origin on the Touch's
//! waist axis at the desk, x towards the operator, z up), the frame the Touch adapters produce.
#pragma once

#include <Eigen/Core>
#include <algorithm>
#include <chrono>
#include <cmath>
#include <limits>
#include <numbers>
#include <string>

#include "endohaptics/core/clock.hpp"
#include "endohaptics/core/error.hpp"
#include "endohaptics/core/parameter.hpp"
#include "endohaptics/kinematics/cylindrical_mapper.hpp"
#include "endohaptics/model/human_arm_model.hpp"
#include "endohaptics/teleop/haptic_device.hpp"

namespace endohaptics::sim {

//! The script: rest open, close (smoothly, raised cosine), hold, open, repeat. The rest (open)
//! pose is the mapper's kinematics::rest_position(): straight ahead at the height and radius where
//! the default CylindricalMapperConfig puts pitch and clamps mid-range (roll 0.0066 rad). Closing
//! takes clamp 1 from 0 rad to +0.6 rad (into the default tissue); the setpoint moves at most
//! ~1.2 rad/s, within what the simulated cascade follows (docs/models/sim.md).
struct OperatorScript {
  double theta = std::numbers::pi / 2;                 //!< rad, stylus azimuth: straight ahead (+x)
  double z = kinematics::rest_position<double>().z();  //!< m, stylus height (0.13740)
  double r_open = kinematics::rest_position<double>().x();  //!< m, radius, clamps open (0.13002)
  double r_closed = 0.0186;   //!< m, radius the hand aims at when grasping
  double open_time = 0.7;     //!< s, resting open at the start of a cycle
  double close_time = 0.8;    //!< s, closing
  double hold_time = 0.7;     //!< s, holding closed
  double release_time = 0.8;  //!< s, opening
  //! rad, added to theta as the hand closes (0 open, all of it closed): the grasp also turns
  //! the wrist (roll, eq. 5.9: 0.71 rad of roll per rad of azimuth). 0: roll stays put.
  double theta_swing = 0.0;
  //! m, added to z as the hand closes: the grasp also lifts the wrist (pitch, eq. 5.9: 3.93 rad
  //! of pitch per m). 0: pitch stays put.
  double z_swing = 0.0;
  //! In [0, 0.95]: cycle k grasps (r, theta and z alike) only a fraction 1 - depth_variation x
  //! frac(k x 0.618...) of the way (golden-ratio steps: the depths fill [1 - variation, 1]
  //! evenly, none repeated), so an identification experiment sees light and firm grasps and
  //! grasps that stop short of the object. 0: every cycle the same.
  double depth_variation = 0.0;
  double arm_sample_time = 1e-3;  //!< s, the arm model's ZOH period

  //! Duration of one open-close-hold-release cycle, s.
  [[nodiscard]] double cycle() const noexcept {
    return open_time + close_time + hold_time + release_time;
  }

  //! Every field but arm_sample_time (the arm model's, not the script's) by its configuration
  //! name, with its bound (core/parameter.hpp): the one list validate() and the bridge
  //! configuration use.
  template <typename Self, typename Visitor>
  static void for_each_field(Self& p, Visitor&& v) {
    constexpr double inf = std::numeric_limits<double>::infinity();
    v("theta", p.theta, Bound::finite("rad"));
    v("z", p.z, Bound::finite("m"));
    v("r_open", p.r_open, Bound::above(0, inf, "m"));
    v("r_closed", p.r_closed, Bound::in(0, inf, "m"));
    v("open_time", p.open_time, Bound::in(0, inf, "s"));
    v("close_time", p.close_time, Bound::above(0, inf, "s"));
    v("hold_time", p.hold_time, Bound::in(0, inf, "s"));
    v("release_time", p.release_time, Bound::above(0, inf, "s"));
    v("theta_swing", p.theta_swing, Bound::in(-std::numbers::pi, std::numbers::pi, "rad"));
    v("z_swing", p.z_swing, Bound::in(-0.5, 0.5, "m"));
    v("depth_variation", p.depth_variation, Bound::in(0, 0.95));
  }

  //! Throws ParameterError naming the field, its value and the rule.
  void validate() const {
    const ParameterChecker check{"OperatorScript"};
    for_each_field(*this, check);
    check("arm_sample_time", arm_sample_time,
          Bound::above(0, std::numeric_limits<double>::infinity(), "s"));
  }

  //! Where the hand aims at time `t` (s since start), m, mapping frame.
  [[nodiscard]] Eigen::Vector3d intent(double t) const noexcept {
    const double c = cycle();
    const double since_start = std::max(t, 0.0);
    double phase = std::fmod(since_start, c);
    const double k = std::floor(since_start / c);  // cycle number
    const double golden = 0.6180339887498949;      // (sqrt 5 - 1) / 2
    const double depth = 1.0 - depth_variation * (k * golden - std::floor(k * golden));
    auto blend = [](double s) { return 0.5 - 0.5 * std::cos(std::numbers::pi * s); };  // 0 -> 1
    double closed = 0.0;  // 0 open, 1 closed
    if (phase < open_time) {
      closed = 0.0;
    } else if ((phase -= open_time) < close_time) {
      closed = blend(phase / close_time);
    } else if ((phase -= close_time) < hold_time) {
      closed = 1.0;
    } else {
      phase -= hold_time;
      closed = 1.0 - blend(std::min(phase / release_time, 1.0));
    }
    closed *= depth;
    const double r = r_open + (r_closed - r_open) * closed;
    const double th = theta + theta_swing * closed;
    return {r * std::sin(th), r * std::cos(th), z + z_swing * closed};  // theta = atan2(x, y)
  }
};

//! teleop::HapticDevice. read(): the hand's intent plus the arm's response (admittance, eq. 5.3)
//! to the force last commanded, the arm stepped at its own period up to the clock's now.
template <endohaptics::Clock ClockT = endohaptics::SteadyClock>
class ScriptedOperator {
 public:
  //! Throws Error on an invalid script or arm. `clock` must outlive the device.
  explicit ScriptedOperator(ClockT& clock, const OperatorScript& script = {},
                            const model::HumanArmParameters<double>& arm = {})
      : clock_(&clock),
        script_((script.validate(), script)),
        arm_(script.arm_sample_time, arm),
        period_(std::chrono::duration_cast<std::chrono::nanoseconds>(
            std::chrono::duration<double>(script.arm_sample_time))),
        start_(clock.now()),
        next_step_(start_) {}

  //! Steps the arm up to the clock's now, writes the stylus position (m), no buttons; ok.
  teleop::DeviceStatus read(teleop::StylusSample& sample) noexcept {
    const auto now = clock_->now();
    int steps = 0;
    while (next_step_ <= now && steps < max_catch_up) {  // bounded: a long pause skips ahead
      Eigen::Vector3d velocity;
      (void)arm_.apply_force(force_, displacement_, velocity);
      next_step_ += period_;
      ++steps;
    }
    if (next_step_ <= now) next_step_ = now + period_;
    sample.position = script_.intent(seconds(now)) + displacement_;
    sample.buttons = 0;
    last_position_ = sample.position;
    return teleop::DeviceStatus::ok;
  }

  //! Force (N, mapping frame) on the hand from now on; a non-finite force is refused (zero force,
  //! error).
  teleop::DeviceStatus command_force(const Eigen::Vector3d& force) noexcept {
    if (!force.allFinite()) {
      force_.setZero();
      return teleop::DeviceStatus::error;  // a real device would refuse it too
    }
    force_ = force;
    return teleop::DeviceStatus::ok;
  }

  [[nodiscard]] const Eigen::Vector3d& force() const noexcept { return force_; }  //!< N, last
  //! Stylus position returned by the last read(), m.
  [[nodiscard]] const Eigen::Vector3d& position() const noexcept { return last_position_; }
  //! Hand's intended position now (without the arm's response), m.
  [[nodiscard]] Eigen::Vector3d intent() const noexcept {
    return script_.intent(seconds(clock_->now()));
  }
  //! The validated script.
  [[nodiscard]] const OperatorScript& script() const noexcept { return script_; }

  static constexpr int max_catch_up = 100;  //!< arm steps per read at most

 private:
  [[nodiscard]] double seconds(std::chrono::nanoseconds t) const noexcept {
    return std::chrono::duration<double>(t - start_).count();
  }

  ClockT* clock_;
  OperatorScript script_;
  model::HumanArm3<double> arm_;
  std::chrono::nanoseconds period_;
  std::chrono::nanoseconds start_;
  std::chrono::nanoseconds next_step_;
  Eigen::Vector3d force_ = Eigen::Vector3d::Zero();
  Eigen::Vector3d displacement_ = Eigen::Vector3d::Zero();
  Eigen::Vector3d last_position_ = Eigen::Vector3d::Zero();
};

static_assert(teleop::HapticDevice<ScriptedOperator<endohaptics::SteadyClock>>);

}  // namespace endohaptics::sim
