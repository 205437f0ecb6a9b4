//! @file
//! HapticDeviceModel: a Geomagic Touch held by the worksheet's arm (5.1, table 5.1), as a
//! teleop::HapticDevice. Per axis the stylus is a mass with damping, driven by the commanded
//! force (limited to the Touch's 3.3 N peak, held over each 1 kHz servo period) and by the hand:
//! the arm model (HumanArmModel, impedance form) whose base follows the operator's intent (a
//! press-and-hold script). Semi-implicit Euler sub-steps. Units: m, m/s, N, kg, s.
#pragma once

#include <Eigen/Core>
#include <algorithm>
#include <chrono>
#include <cmath>
#include <numbers>
#include <string>

#include "endohaptics/core/clock.hpp"
#include "endohaptics/core/error.hpp"
#include "endohaptics/model/human_arm_model.hpp"
#include "endohaptics/teleop/haptic_device.hpp"

namespace endohaptics::sim {

//! The device (a Geomagic Touch's order of magnitude; see docs/passivity.md).
struct DeviceParameters {
  double mass = 0.045;         //!< kg, apparent stylus mass per axis
  double damping = 0.05;       //!< N s/m, the device's own viscous damping
  double force_limit = 3.3;    //!< N, peak force the device renders (magnitude)
  double servo_period = 1e-3;  //!< s, the force is held over this period (1 kHz servo)
  int substeps = 10;           //!< integration steps per servo period

  //! Throws Error naming the field and value.
  void validate() const {
    auto check = [](bool ok, const char* field, double v) {
      if (!ok) {
        ENDOHAPTICS_THROW(Error(std::string("DeviceParameters: ") + field +
                                " out of range: " + endohaptics::detail::format_number(v)));
      }
    };
    check(std::isfinite(mass) && mass > 0.0, "mass (kg)", mass);
    check(std::isfinite(damping) && damping >= 0.0, "damping (N s/m)", damping);
    check(std::isfinite(force_limit) && force_limit > 0.0, "force_limit (N)", force_limit);
    check(std::isfinite(servo_period) && servo_period > 0.0 && servo_period <= 0.1,
          "servo_period (s)", servo_period);
    check(substeps >= 1 && substeps <= 1000, "substeps", substeps);
  }
};

//! The operator's intent: rest at `start`, then move the arm's base by `travel` (m, mapping
//! frame) over `approach_time` (raised cosine) starting at `approach_start`, then hold.
struct PressScript {
  Eigen::Vector3d start = Eigen::Vector3d::Zero();   //!< m, where the hand rests at first
  Eigen::Vector3d travel = Eigen::Vector3d::Zero();  //!< m, how far the base moves
  double approach_start = 0.5;                       //!< s after construction
  double approach_time = 1.0;                        //!< s, > 0

  //! Throws Error naming the field and value.
  void validate() const {
    if (!start.allFinite() || !travel.allFinite()) {
      ENDOHAPTICS_THROW(Error("PressScript: start and travel must be finite"));
    }
    if (!std::isfinite(approach_start) || approach_start < 0.0) {
      ENDOHAPTICS_THROW(Error("PressScript: approach_start must be >= 0 s, got " +
                              endohaptics::detail::format_number(approach_start)));
    }
    if (!std::isfinite(approach_time) || !(approach_time > 0.0)) {
      ENDOHAPTICS_THROW(Error("PressScript: approach_time must be > 0 s, got " +
                              endohaptics::detail::format_number(approach_time)));
    }
  }
  //! The base position at `t` s, m.
  [[nodiscard]] Eigen::Vector3d intent(double t) const noexcept {
    const double s = std::clamp((t - approach_start) / approach_time, 0.0, 1.0);
    return start + travel * (0.5 - 0.5 * std::cos(std::numbers::pi * s));
  }
};

//! teleop::HapticDevice on a clock: read() integrates the stylus and the arm up to the clock's
//! now (at most max_catch_up servo periods per call), command_force() sets the force of the
//! following servo periods. Every call is noexcept and allocation-free.
template <endohaptics::Clock ClockT = endohaptics::SteadyClock>
class HapticDeviceModel {
 public:
  static constexpr int max_catch_up = 1000;  //!< servo periods per read at most

  //! Throws Error on invalid parameters. `clock` must outlive the device.
  HapticDeviceModel(ClockT& clock, const PressScript& script, const DeviceParameters& device = {},
                    const model::HumanArmParameters<double>& arm = {})
      : clock_(&clock),
        script_((script.validate(), script)),
        device_((device.validate(), device)),
        h_(device.servo_period / device.substeps),
        arm_(h_, arm),
        period_(std::chrono::duration_cast<std::chrono::nanoseconds>(
            std::chrono::duration<double>(device.servo_period))),
        start_(clock.now()),
        next_servo_(start_),
        position_(script.start) {}

  //! Advances to the clock's now and writes the stylus position (m), no buttons; ok.
  teleop::DeviceStatus read(teleop::StylusSample& sample) noexcept {
    const auto now = clock_->now();
    int periods = 0;
    while (next_servo_ <= now && periods < max_catch_up) {
      servo_period();
      next_servo_ += period_;
      ++periods;
    }
    if (next_servo_ <= now) next_servo_ = now + period_;
    sample.position = position_;
    sample.buttons = 0;
    return teleop::DeviceStatus::ok;
  }

  //! Force (N) from the next servo period on, scaled down to force_limit; a non-finite force is
  //! refused (zero force, error).
  teleop::DeviceStatus command_force(const Eigen::Vector3d& force) noexcept {
    if (!force.allFinite()) {
      force_.setZero();
      return teleop::DeviceStatus::error;
    }
    const double norm = force.norm();
    force_ =
        norm > device_.force_limit ? Eigen::Vector3d(force * (device_.force_limit / norm)) : force;
    commanded_norm_ = norm;
    return teleop::DeviceStatus::ok;
  }

  //! Stylus position, m (mapping frame).
  [[nodiscard]] const Eigen::Vector3d& position() const noexcept { return position_; }
  //! Stylus velocity, m/s.
  [[nodiscard]] const Eigen::Vector3d& velocity() const noexcept { return velocity_; }
  //! Force the device renders now, N (after its limit).
  [[nodiscard]] const Eigen::Vector3d& force() const noexcept { return force_; }
  //! Magnitude of the force last commanded before the device's limit, N.
  [[nodiscard]] double commanded_norm() const noexcept { return commanded_norm_; }
  //! Force the hand exerts on the stylus, N.
  [[nodiscard]] const Eigen::Vector3d& hand_force() const noexcept { return hand_force_; }
  //! The arm's base (the operator's intent) now, m.
  [[nodiscard]] Eigen::Vector3d intent() const noexcept { return script_.intent(seconds()); }
  //! Energy the device's force did on the hand and stylus so far, J.
  [[nodiscard]] double work() const noexcept { return work_; }
  //! The validated script.
  [[nodiscard]] const PressScript& script() const noexcept { return script_; }

 private:
  [[nodiscard]] double seconds() const noexcept {
    return std::chrono::duration<double>(clock_->now() - start_).count();
  }

  // One servo period: the force held, the stylus mass and the arm stepped in sub-steps.
  void servo_period() noexcept {
    const double t0 = std::chrono::duration<double>(next_servo_ - start_).count();
    for (int k = 0; k < device_.substeps; ++k) {
      const double t = t0 + k * h_;
      const Eigen::Vector3d base = script_.intent(t);
      const Eigen::Vector3d base_velocity = (script_.intent(t + h_) - base) / h_;
      Eigen::Vector3d on_hand;  // force the stylus exerts on the hand (eq. 5.1)
      (void)arm_.impose_motion(position_ - base, velocity_ - base_velocity, on_hand);
      hand_force_ = -on_hand;
      const Eigen::Vector3d acceleration =
          (force_ - device_.damping * velocity_ + hand_force_) / device_.mass;
      velocity_ += h_ * acceleration;
      const Eigen::Vector3d step = h_ * velocity_;
      work_ += force_.dot(step);
      position_ += step;
    }
  }

  ClockT* clock_;
  PressScript script_;
  DeviceParameters device_;
  double h_;
  model::HumanArm3<double> arm_;
  std::chrono::nanoseconds period_;
  std::chrono::nanoseconds start_;
  std::chrono::nanoseconds next_servo_;
  Eigen::Vector3d position_;
  Eigen::Vector3d velocity_ = Eigen::Vector3d::Zero();
  Eigen::Vector3d force_ = Eigen::Vector3d::Zero();
  Eigen::Vector3d hand_force_ = Eigen::Vector3d::Zero();
  double commanded_norm_ = 0.0;
  double work_ = 0.0;
};

static_assert(teleop::HapticDevice<HapticDeviceModel<endohaptics::SteadyClock>>);

}  // namespace endohaptics::sim
