//! @file
//! CylindricalMapper: Geomagic Touch stylus position -> EndoWrist joint setpoints (eq. 5.9) and
//! tool joint forces -> stylus force (eq. 5.8), worksheet 5.5 and figure 5.14.
//! Units: position in m, theta and setpoints in rad (motor side, after gearing), forces in N.
//!
//! The mapping frame (the one definition every device adapter converts into; details and what is
//! measured vs assumed: docs/models/cylindrical_mapper.md):
//!  - origin O_c on the Touch's waist (vertical) axis, at the underside of its base (the desk);
//!  - +z up, along the waist axis; +x horizontal, from the waist axis towards the operator, i.e.
//!    where the arm points with the waist centred: the neutral direction, theta = pi/2;
//!  - +y = z x x (right-handed): the operator's right; theta = atan2(x, y) grows from +y to +x.
//! The 2016 coefficients put mid-range setpoints at the rest pose `rest_position()`: stylus
//! straight ahead (theta = pi/2), r = b_clamp / a_clamp = 0.130 m, z = -b_pitch / a_pitch = 0.137
//! m.
#pragma once

#include <Eigen/Core>
#include <array>
#include <cmath>
#include <cstdint>
#include <limits>
#include <numbers>
#include <string>
#include <string_view>

#include "endohaptics/core/error.hpp"
#include "endohaptics/core/numeric_status.hpp"
#include "endohaptics/core/parameter.hpp"
#include "endohaptics/protocol/motor_order.hpp"

namespace endohaptics::kinematics {

using protocol::Motor;

//! A mapping returns `NumericStatus` (core/numeric_status.hpp); on anything but `ok` the caller's
//! output is left untouched.
using endohaptics::NumericStatus;

//! Cylindrical coordinates of the stylus (figure 5.14).
template <typename Scalar = double>
struct Cylindrical {
  Scalar theta{};  //!< rad, from +y towards +x: theta = atan2(x, y)
  Scalar r{};      //!< m, horizontal distance O_c -> O_p
  Scalar z{};      //!< m, height
};

//! What `map_position` did.
template <typename Scalar = double>
struct [[nodiscard]] PositionResult {
  NumericStatus status = NumericStatus::ok;  //!< ok, or why the mapping was refused
  std::uint8_t clamped_mask = 0;             //!< bit j: tool joint j was limited to its range
  bool theta_held = false;                   //!< r <= min_radius: theta is the last valid one
  Cylindrical<Scalar> coordinates{};         //!< the (theta, r, z) used; meaningful only when ok

  //! True when `status` is ok (setpoints written).
  [[nodiscard]] constexpr bool ok() const noexcept { return status == NumericStatus::ok; }
  //! True when `joint` was limited to its range.
  [[nodiscard]] constexpr bool clamped(Motor joint) const noexcept {
    return ((clamped_mask >> static_cast<unsigned>(joint)) & 1u) != 0;
  }
};

//! What `map_force` did.
struct [[nodiscard]] ForceResult {
  NumericStatus status = NumericStatus::ok;  //!< ok, or why the mapping was refused
  //! Bit k: channel k (0 clamp/radial, 1 roll/tangential, 2 pitch/vertical) was limited to
  //! `channel_limit[k]` (sign kept).
  std::uint8_t channel_limited_mask = 0;
  bool limited = false;  //!< the force was then scaled down to `force_limit` (direction kept)

  //! True when `status` is ok (force written).
  [[nodiscard]] constexpr bool ok() const noexcept { return status == NumericStatus::ok; }
};

//! Configuration of eq. 5.9 and 5.8. Defaults: the 2016 rig (docs/models/cylindrical_mapper.md
//! says which are from the worksheet, which are assumptions, and which units they assume).
template <typename Scalar = double>
struct CylindricalMapperConfig {
  using Vector3 = Eigen::Matrix<Scalar, 3, 1>;  //!< per cylindrical axis
  using Vector4 = Eigen::Matrix<Scalar, 4, 1>;  //!< per tool joint (index = Motor)

  Scalar a_roll = Scalar(0.7096);  //!< rad/rad: P_roll = a_roll theta + b_roll
  Scalar b_roll = Scalar(-1.108);  //!< rad
  Scalar a_pitch = Scalar(3.93);   //!< rad/m: P_pitch = a_pitch z + b_pitch
  Scalar b_pitch = Scalar(-0.54);  //!< rad
  Scalar a_clamp = Scalar(5.384);  //!< rad/m: P_clamp1 = -a_clamp r + b_clamp, P_clamp2 = -P_clamp1
  Scalar b_clamp = Scalar(0.7);    //!< rad
  //! motor_order[m]: the tool joint driven by motor slot m (a permutation).
  std::array<Motor, 4> motor_order = {Motor::roll, Motor::pitch, Motor::clamp1, Motor::clamp2};
  //! rad, per tool joint (index = Motor); assumption: the +-1.028 rad of the 2016 tuning logs.
  Vector4 lower = Vector4::Constant(Scalar(-protocol::endowrist_joint_range));
  //! rad, per tool joint
  Vector4 upper = Vector4::Constant(Scalar(protocol::endowrist_joint_range));
  Scalar min_radius = Scalar(1e-3);  //!< m; at r <= min_radius theta is held (undefined at 0)
  //! rad, in [-pi, pi]: theta is reported in (neutral - pi, neutral + pi], and held at this
  //! value until the first position with r > min_radius.
  Scalar theta_neutral = std::numbers::pi_v<Scalar> / 2;
  //! Per cylindrical axis (clamp/radial, roll/tangential, pitch/vertical), N per tool-force unit,
  //! >= 0: a negative scale would turn the feedback to push along the operator's motion.
  Vector3 force_scale = Vector3::Ones();
  //! N, > 0, per channel (clamp, roll, pitch), applied before `force_limit` so that one wrong
  //! joint estimate cannot crowd out the others. 1.4 N <= force_limit / sqrt(3) = 1.44 N: with the
  //! defaults the shared limit never scales a force whose channels are each within their limit.
  Vector3 channel_limit = Vector3::Constant(Scalar(1.4));
  Scalar force_limit = Scalar(2.5);  //!< N, magnitude limit of the stylus force (Touch peak 3.3)
  //! m, >= 0: inside this radius the roll (tangential) channel is multiplied by r / this radius.
  //! Eq. 5.9 turns a tangential stylus move ds into a_roll ds / r of roll, so the roll a
  //! compliant hand gives back under the rendered roll force grows as 1 / r towards the waist
  //! axis; scaled so, it stays at its value at this radius (docs/models/cylindrical_mapper.md,
  //! "The roll channel near the waist axis"). 0 (default): eq. 5.8 verbatim at every r. The
  //! geometric choice is the rest radius, rest_position(config).x() (b_clamp / a_clamp = 0.130015
  //! m with the defaults): the radius eq. 5.9 is centred on.
  Scalar roll_lever_radius = Scalar(0);

  //! Every field but motor_order (a permutation, checked by CylindricalMapper) by its
  //! configuration name, with its bound (core/parameter.hpp): the one list CylindricalMapper's
  //! validation and the bridge configuration use.
  template <typename Self, typename Visitor>
  static void for_each_field(Self& p, Visitor&& v) {
    constexpr double pi = std::numbers::pi;
    // The gains of eq. 5.9 scale the motion and, through eq. 5.8's transpose, the force felt:
    // a gain of 0 would freeze the joint and silently remove its force feedback.
    const Bound gain = Bound::magnitude(1e-6, 1e6).described(
        "of magnitude in [1e-6, 1e6] (a gain of 0 freezes the joint and removes its force "
        "feedback)");
    const Bound angle = Bound::in(-pi, pi, "rad").described("in [-pi, pi] rad");
    // Per channel before the shared force_limit (the bridge holds both to the Touch's peak).
    const Bound force = Bound::above(0, std::numeric_limits<double>::infinity(), "N");
    v("a_roll", p.a_roll, gain);
    v("b_roll", p.b_roll, Bound::finite("rad"));
    v("a_pitch", p.a_pitch, gain);
    v("b_pitch", p.b_pitch, Bound::finite("rad"));
    v("a_clamp", p.a_clamp, gain);
    v("b_clamp", p.b_clamp, Bound::finite("rad"));
    v("lower", p.lower, Bound::finite("rad"));
    v("upper", p.upper, Bound::finite("rad"));
    v("min_radius", p.min_radius, Bound::in(0, std::numeric_limits<double>::infinity(), "m"));
    v("theta_neutral", p.theta_neutral, angle);
    // >= 0: a negative scale would push along the operator's motion.
    v("force_scale", p.force_scale, Bound::in(0, 100, "N per unit"));
    v("force_limit", p.force_limit, force);
    v("channel_limit", p.channel_limit, force);
    v("roll_lever_radius", p.roll_lever_radius,
      Bound::in(0, std::numeric_limits<double>::infinity(), "m"));
  }
};

//! The rest pose of the mapping frame (m): the stylus straight ahead (theta = pi/2, +x) at the
//! radius where the clamp setpoints and the height where the pitch setpoint are mid-range,
//! r = (b_clamp - (lower + upper)[clamp1] / 2) / a_clamp, z = ((lower + upper)[pitch] / 2 -
//! b_pitch) / a_pitch. 2016 defaults: (0.13002, 0, 0.13740); roll there is 0.0066 rad.
//! Throws endohaptics::Error when a_clamp or a_pitch is 0 (no such height or radius).
template <typename Scalar = double>
[[nodiscard]] Eigen::Matrix<Scalar, 3, 1> rest_position(
    const CylindricalMapperConfig<Scalar>& config = {}) {
  if (!(config.a_clamp != 0) || !(config.a_pitch != 0)) {
    ENDOHAPTICS_THROW(Error("rest_position: a_clamp and a_pitch must be non-zero, got a_clamp " +
                            endohaptics::detail::format_number(config.a_clamp) + ", a_pitch " +
                            endohaptics::detail::format_number(config.a_pitch)));
  }
  const auto clamp1 = static_cast<Eigen::Index>(Motor::clamp1);
  const auto pitch = static_cast<Eigen::Index>(Motor::pitch);
  const Scalar clamp_mid = (config.lower[clamp1] + config.upper[clamp1]) / 2;
  const Scalar pitch_mid = (config.lower[pitch] + config.upper[pitch]) / 2;
  return {(config.b_clamp - clamp_mid) / config.a_clamp, Scalar(0),
          (pitch_mid - config.b_pitch) / config.a_pitch};
}

//! Eq. 5.9 (position -> joint setpoints, with per-joint range limits) and eq. 5.8 (joint forces
//! -> stylus force, with a magnitude limit). Per-tick functions are noexcept and allocation-free.
template <typename Scalar = double>
class CylindricalMapper {
 public:
  static constexpr int num_joints = 4;              //!< EndoWrist tool joints (= motors)
  static constexpr Scalar min_gain = Scalar(1e-6);  //!< smallest |a_roll|, |a_pitch|, |a_clamp|
  static constexpr Scalar max_gain = Scalar(1e6);   //!< largest |a_roll|, |a_pitch|, |a_clamp|
  using Config = CylindricalMapperConfig<Scalar>;   //!< eq. 5.8/5.9 parameters
  using Vector3 = Eigen::Matrix<Scalar, 3, 1>;      //!< stylus position (m) or force (N)
  using MotorVector = Eigen::Matrix<Scalar, num_joints, 1>;  //!< motor order
  using Coordinates = Cylindrical<Scalar>;                   //!< (theta, r, z) of the stylus

  //! Validates `config`; throws endohaptics::Error naming the bad field and its value.
  explicit CylindricalMapper(const Config& config = Config{}) : config_(config) {
    validate();
    held_theta_ = config_.theta_neutral;
    held_radius_ = std::numeric_limits<Scalar>::infinity();
  }

  //! The validated configuration.
  [[nodiscard]] const Config& config() const noexcept { return config_; }

  //! Eq. 5.9: stylus position (m, mapping frame) -> setpoints (rad, motor order), each limited to
  //! its range. Updates the held theta. `setpoint` is untouched unless the result is ok.
  PositionResult<Scalar> map_position(const Vector3& position, MotorVector& setpoint) noexcept {
    PositionResult<Scalar> result;
    if (!position.allFinite()) {
      result.status = NumericStatus::non_finite_input;
      return result;
    }
    const Scalar r = std::hypot(position.x(), position.y());
    Scalar theta = held_theta_;
    if (r > config_.min_radius) {
      theta = wrap(std::atan2(position.x(), position.y()));
    } else {
      result.theta_held = true;
    }
    std::array<Scalar, num_joints> p{};
    p[index(Motor::roll)] = config_.a_roll * theta + config_.b_roll;
    p[index(Motor::pitch)] = config_.a_pitch * position.z() + config_.b_pitch;
    p[index(Motor::clamp1)] = -config_.a_clamp * r + config_.b_clamp;
    p[index(Motor::clamp2)] = config_.a_clamp * r - config_.b_clamp;
    for (std::size_t j = 0; j < p.size(); ++j) {
      const auto i = static_cast<Eigen::Index>(j);
      if (std::isnan(p[j])) {  // only 0 * inf (huge input with a zero scale) gets here
        result.status = NumericStatus::non_finite_input;
        return result;
      }
      if (p[j] < config_.lower[i]) {
        p[j] = config_.lower[i];
        result.clamped_mask = static_cast<std::uint8_t>(result.clamped_mask | (1u << j));
      } else if (p[j] > config_.upper[i]) {
        p[j] = config_.upper[i];
        result.clamped_mask = static_cast<std::uint8_t>(result.clamped_mask | (1u << j));
      }
    }
    for (int m = 0; m < num_joints; ++m) {
      setpoint[m] = p[index(config_.motor_order[static_cast<std::size_t>(m)])];
    }
    held_theta_ = theta;
    held_radius_ = r;
    result.coordinates = Coordinates{theta, r, position.z()};
    return result;
  }

  //! Eq. 5.8 at stylus angle `theta` (rad) and radius `radius` (m): joint forces (motor order;
  //! each the external force on that joint, positive along its positive setpoint) -> stylus force
  //! (N, mapping frame), scaled and limited per channel, then limited in magnitude. sign(a_i)
  //! makes each channel oppose the stylus motion that would drive its joint further against the
  //! force (docs: "Signs of a"). The roll channel is also multiplied by
  //! min(1, radius / roll_lever_radius) (the roll gain of eq. 5.9 goes as 1 / r; docs: "The roll
  //! channel near the waist axis"). `stylus_force` is untouched unless the result is ok
  //! (a NaN or negative radius is refused; +infinity means "far from the axis").
  ForceResult map_force(const MotorVector& motor_force, Scalar theta, Scalar radius,
                        Vector3& stylus_force) const noexcept {
    ForceResult result;
    if (!motor_force.allFinite() || !std::isfinite(theta) || !(radius >= Scalar(0))) {
      result.status = NumericStatus::non_finite_input;
      return result;
    }
    const Scalar f_roll = motor_force[motor_of(Motor::roll)];
    const Scalar f_pitch = motor_force[motor_of(Motor::pitch)];
    const Scalar f_clamp1 = motor_force[motor_of(Motor::clamp1)];
    const Scalar f_clamp2 = motor_force[motor_of(Motor::clamp2)];
    // Generalised forces along r, theta, z (virtual work: P_clamp2 grows with r, P_clamp1 falls).
    std::array<Scalar, 3> channel = {
        sign(config_.a_clamp) * (f_clamp2 - f_clamp1) / 2 * config_.force_scale[0],
        sign(config_.a_roll) * f_roll * config_.force_scale[1] * roll_lever(radius),
        sign(config_.a_pitch) * f_pitch * config_.force_scale[2]};
    for (std::size_t k = 0; k < channel.size(); ++k) {
      const Scalar limit = config_.channel_limit[static_cast<Eigen::Index>(k)];
      if (std::fabs(channel[k]) > limit) {  // an overflow to inf is limited too
        channel[k] = std::copysign(limit, channel[k]);
        result.channel_limited_mask =
            static_cast<std::uint8_t>(result.channel_limited_mask | (1u << k));
      }
    }
    const Scalar clamp = channel[0];
    const Scalar roll = channel[1];
    const Scalar pitch = channel[2];
    const Scalar s = std::sin(theta);
    const Scalar c = std::cos(theta);
    Vector3 force(clamp * s + roll * c, clamp * c - roll * s, pitch);
    if (!force.allFinite()) {
      result.status = NumericStatus::non_finite_input;
      return result;
    }
    const Scalar magnitude = force.stableNorm();
    if (magnitude > config_.force_limit) {
      force *= config_.force_limit / magnitude;
      result.limited = true;
    }
    stylus_force = force;
    return result;
  }

  //! Eq. 5.8 at stylus angle `theta` with the radius not known: as at r >= roll_lever_radius
  //! (the roll channel unscaled, eq. 5.8 verbatim).
  ForceResult map_force(const MotorVector& motor_force, Scalar theta,
                        Vector3& stylus_force) const noexcept {
    return map_force(motor_force, theta, std::numeric_limits<Scalar>::infinity(), stylus_force);
  }

  //! Eq. 5.8 at the theta and radius of the last successful `map_position` (before any:
  //! `theta_neutral`, radius not known). What the teleoperation loop renders.
  ForceResult map_force(const MotorVector& motor_force, Vector3& stylus_force) const noexcept {
    return map_force(motor_force, held_theta_, held_radius_, stylus_force);
  }

  //! The factor on the roll channel at stylus radius `radius` (m, >= 0): min(1, radius /
  //! roll_lever_radius); 1 when roll_lever_radius is 0 or radius is +infinity.
  [[nodiscard]] Scalar roll_lever(Scalar radius) const noexcept {
    const Scalar lever = config_.roll_lever_radius;
    return radius >= lever ? Scalar(1) : radius / lever;
  }

  //! Per motor slot, the largest joint force (N) that eq. 5.8 renders without its channel's
  //! `channel_limit` clipping it, with the other joints at zero: channel_limit / force_scale, and
  //! twice that for the clamps (a clamp's share of the radial channel is half its force);
  //! +infinity where the channel's scale is 0. For roll, the value at r >= roll_lever_radius
  //! (inside it the lever lets a larger roll force through unclipped: this is the lower bound). For
  //! layers that must know what the operator feels unclipped
  //! (teleop::PassivityConfig::force_limit).
  [[nodiscard]] MotorVector unclipped_joint_force() const noexcept {
    MotorVector limit;
    for (std::size_t m = 0; m < config_.motor_order.size(); ++m) {
      const Motor joint = config_.motor_order[m];
      const Eigen::Index channel = joint == Motor::roll ? 1 : joint == Motor::pitch ? 2 : 0;
      const Scalar share = channel == 0 ? Scalar(2) : Scalar(1);
      const Scalar scale = config_.force_scale[channel];
      limit[static_cast<Eigen::Index>(m)] = scale > Scalar(0)
                                                ? share * config_.channel_limit[channel] / scale
                                                : std::numeric_limits<Scalar>::infinity();
    }
    return limit;
  }

  //! Inverse of eq. 5.8 without scale or limit: stylus force (N) at `theta` -> (F_clamp along
  //! e_r, F_roll along e_theta, F_pitch along z). Precondition: finite inputs (NaN in, NaN out).
  [[nodiscard]] static Vector3 cylindrical_force(const Vector3& stylus_force,
                                                 Scalar theta) noexcept {
    const Scalar s = std::sin(theta);
    const Scalar c = std::cos(theta);
    return Vector3(stylus_force.x() * s + stylus_force.y() * c,
                   stylus_force.x() * c - stylus_force.y() * s, stylus_force.z());
  }

  //! The theta of the last successful `map_position` (rad), or `theta_neutral` before it.
  [[nodiscard]] Scalar theta() const noexcept { return held_theta_; }

  //! The r (m) of the last successful `map_position`, or +infinity (not known) before it.
  [[nodiscard]] Scalar radius() const noexcept { return held_radius_; }

  //! Forgets the held theta and radius: back to `theta_neutral` and "radius not known".
  void reset() noexcept {
    held_theta_ = config_.theta_neutral;
    held_radius_ = std::numeric_limits<Scalar>::infinity();
  }

 private:
  static constexpr std::size_t index(Motor joint) noexcept {
    return static_cast<std::size_t>(joint);
  }
  Eigen::Index motor_of(Motor joint) const noexcept {
    return static_cast<Eigen::Index>(motor_of_joint_[index(joint)]);
  }
  static constexpr Scalar sign(Scalar x) noexcept {
    return x > Scalar(0) ? Scalar(1) : (x < Scalar(0) ? Scalar(-1) : Scalar(0));
  }

  // atan2 gives [-pi, pi]; move it into (neutral - pi, neutral + pi]. One step suffices because
  // theta_neutral is in [-pi, pi].
  Scalar wrap(Scalar theta) const noexcept {
    constexpr Scalar pi = std::numbers::pi_v<Scalar>;
    if (theta <= config_.theta_neutral - pi) theta += 2 * pi;
    if (theta > config_.theta_neutral + pi) theta -= 2 * pi;
    return theta;
  }

  void validate() {
    const ParameterChecker check{"CylindricalMapper"};
    Config::for_each_field(config_, check);
    for (int j = 0; j < num_joints; ++j) {
      const std::string name(to_string(static_cast<Motor>(j)));
      if (config_.lower[j] > config_.upper[j]) {
        ENDOHAPTICS_THROW(Error("CylindricalMapper: range of " + name + " is empty: lower " +
                                endohaptics::detail::format_number(config_.lower[j]) + " > upper " +
                                endohaptics::detail::format_number(config_.upper[j])));
      }
    }
    std::array<bool, num_joints> seen{};
    for (std::size_t m = 0; m < config_.motor_order.size(); ++m) {
      const auto j = static_cast<unsigned>(config_.motor_order[m]);
      if (j >= static_cast<unsigned>(num_joints)) {
        ENDOHAPTICS_THROW(Error("CylindricalMapper: motor_order[" + std::to_string(m) +
                                "] is not a tool joint: " + std::to_string(j)));
      }
      if (seen[j]) {
        ENDOHAPTICS_THROW(Error("CylindricalMapper: motor_order is not a permutation: " +
                                std::string(to_string(config_.motor_order[m])) +
                                " appears twice (again at motor " + std::to_string(m) + ")"));
      }
      seen[j] = true;
      motor_of_joint_[j] = static_cast<int>(m);
    }
  }

  Config config_;
  std::array<int, num_joints> motor_of_joint_{};  // inverse of motor_order
  Scalar held_theta_{};
  Scalar held_radius_{};
};

}  // namespace endohaptics::kinematics
