//! @file
//! Per-joint EndoWrist friction in the motor-current domain (worksheet 5.2, eqs. 5.4-5.7,
//! table 5.2): viscous F_mu*omega + Coulomb sign(omega)*Kc while sliding, static Ks at standstill,
//! and the 5.2.3 gate that feeds an estimated force back only once the current overcomes friction.
//! Currents in A, velocities in rad/s (motor side, after gearing), F_mu in A s/rad. Identification
//! from logs: identification/friction_fit.hpp. See docs/models/friction_model.md.
#pragma once

#include <Eigen/Core>
#include <algorithm>
#include <array>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <string>
#include <string_view>
#include <type_traits>

#include "endohaptics/core/error.hpp"
#include "endohaptics/core/numeric_status.hpp"

namespace endohaptics::model {

//! A per-tick friction call returns `NumericStatus` (core/numeric_status.hpp): a joint with a
//! non-finite current, velocity or estimate has its gate closed and its outputs 0, never skipped.
using endohaptics::NumericStatus;

//! Friction constants of one joint, all >= 0 (signs: docs/models/friction_model.md).
template <typename Scalar = double>
struct JointFriction {
  Scalar static_level = 0;   //!< Ks, A: |current| that breaks the joint away from standstill
  Scalar coulomb_level = 0;  //!< Kc, A: current spent on friction while sliding (eq. 5.7)
  Scalar viscous_gain = 0;   //!< F_mu, A s/rad: extra friction current per rad/s (eq. 5.5)

  //! The simplified 2016 model (5.2.2 "Results"): Kc = Ks = level, F_mu = 0.
  [[nodiscard]] static constexpr JointFriction simplified(Scalar level) noexcept {
    return {level, level, Scalar(0)};
  }
  //! Member-wise equality.
  friend bool operator==(const JointFriction&, const JointFriction&) = default;
};

//! The static levels of an array of JointFriction as a vector of numbers (a field of a parameter
//! list, core/parameter.hpp): element i reads friction[i].static_level, set(i, level) makes
//! friction[i] the simplified model of that level. Configuration time.
template <typename Array>
class StaticFrictionLevels {
 public:
  //! A view of `friction` (const for reading only).
  explicit StaticFrictionLevels(Array& friction) noexcept : a_(friction) {}
  //! The number of joints.
  [[nodiscard]] long size() const noexcept { return static_cast<long>(a_.size()); }
  //! friction[i].static_level.
  [[nodiscard]] auto operator[](long i) const noexcept {
    return a_[static_cast<std::size_t>(i)].static_level;
  }
  //! friction[i] = JointFriction::simplified(level).
  template <typename Scalar>
  void set(long i, Scalar level) noexcept {
    using Friction = std::remove_cvref_t<decltype(a_[0])>;
    a_[static_cast<std::size_t>(i)] =
        Friction::simplified(static_cast<decltype(Friction::static_level)>(level));
  }

 private:
  Array& a_;
};

//! Table 5.2 presets (simplified model, Kc = Ks, F_mu = 0), in A. The roll value is doubtful:
//! the 2016 analysis script and the logs give about 0.13 A (docs/models/friction_model.md).
namespace friction_2016 {
//! Roll: 0.7 A (doubtful, see above).
inline constexpr JointFriction<double> roll = JointFriction<double>::simplified(0.7);
//! Pitch: 0.17 A.
inline constexpr JointFriction<double> pitch = JointFriction<double>::simplified(0.17);
//! Yaw: 0.21 A.
inline constexpr JointFriction<double> yaw = JointFriction<double>::simplified(0.21);
//! Clamp: 0.20 A.
inline constexpr JointFriction<double> clamp = JointFriction<double>::simplified(0.20);
//! Joint order of `endowrist_2016_friction` (the row order of table 5.2).
enum Joint : int { roll_joint = 0, pitch_joint = 1, yaw_joint = 2, clamp_joint = 3 };
}  // namespace friction_2016

//! Thresholds of the model and of the 5.2.3 gate.
template <typename Scalar = double>
struct FrictionOptions {
  //! |omega| <= this counts as "omega == 0" of eqs. 5.6/5.7, rad/s. Must exceed the velocity
  //! noise of the source (0.01 rad/s ~ 1.2 encoder ticks per 10 ms sample).
  Scalar standstill_velocity = Scalar(0.01);
  //! An open gate closes when |current| < release_fraction * level; 1 reproduces the 2016 gate
  //! (no hysteresis). 0.75 leaves a band wider than the ~0.035 A peak current noise at 0.2 A.
  Scalar release_fraction = Scalar(0.75);
};

//! Friction model and force-feedback gate for N joints (eqs. 5.4-5.7, section 5.2.3).
//! Per-tick calls are noexcept, allocation-free and write caller-owned outputs.
template <int N, typename Scalar = double>
class FrictionModel {
  static_assert(N >= 1, "FrictionModel needs at least one joint (N >= 1)");
  static_assert(std::is_floating_point_v<Scalar>, "FrictionModel Scalar must be floating point");

 public:
  static constexpr int joints = N;             //!< number of joints
  using Vector = Eigen::Matrix<Scalar, N, 1>;  //!< one value per joint
  using Joint = JointFriction<Scalar>;         //!< friction constants of one joint
  using Joints = std::array<Joint, static_cast<std::size_t>(N)>;  //!< constants of every joint
  using Options = FrictionOptions<Scalar>;  //!< thresholds of the model and gate
  using GateState = std::array<bool, static_cast<std::size_t>(N)>;  //!< per joint: gate open

  //! Throws Error when a constant is negative or not finite, standstill_velocity is negative or
  //! not finite, or release_fraction is outside (0, 1]; the message names joint, field, value.
  explicit FrictionModel(const Joints& joint_constants, const Options& options = {})
      : joints_(joint_constants), options_(options) {
    for (std::size_t j = 0; j < joints_.size(); ++j) {
      check_level(joints_[j].static_level, j, "static_level (Ks)");
      check_level(joints_[j].coulomb_level, j, "coulomb_level (Kc)");
      check_level(joints_[j].viscous_gain, j, "viscous_gain (F_mu)");
    }
    if (!std::isfinite(options_.standstill_velocity) || options_.standstill_velocity < 0) {
      ENDOHAPTICS_THROW(
          Error("FrictionModel: standstill_velocity must be finite and >= 0 rad/s, got " +
                endohaptics::detail::format_number(options_.standstill_velocity)));
    }
    if (!(options_.release_fraction > 0 && options_.release_fraction <= 1)) {
      ENDOHAPTICS_THROW(Error("FrictionModel: release_fraction must lie in (0, 1], got " +
                              endohaptics::detail::format_number(options_.release_fraction)));
    }
  }

  //! Constants of joint `j`. Precondition: 0 <= j < N.
  [[nodiscard]] const Joint& joint(int j) const noexcept {
    ENDOHAPTICS_ASSERT(j >= 0 && j < N);
    return joints_[static_cast<std::size_t>(j)];
  }
  [[nodiscard]] const Options& options() const noexcept { return options_; }  //!< thresholds
  //! Gate state per joint: true while the estimate is fed back.
  [[nodiscard]] const GateState& gate_open() const noexcept { return open_; }
  //! Closes every gate.
  void reset() noexcept { open_.fill(false); }

  //! |current| friction can absorb at `velocity`: Ks at standstill, Kc + F_mu |omega| when
  //! sliding. A non-finite velocity gives level 0 for that joint and `non_finite_input`.
  [[nodiscard]] NumericStatus breakaway_level(const Vector& velocity,
                                              Vector& level) const noexcept {
    NumericStatus status = NumericStatus::ok;
    for (int j = 0; j < N; ++j) {
      if (!std::isfinite(velocity[j])) {
        level[j] = 0;
        status = NumericStatus::non_finite_input;
        continue;
      }
      level[j] = level_of(j, velocity[j]);
    }
    return status;
  }

  //! Current spent on friction (eq. 5.4, sign of the motion): F_mu omega + Kc sign(omega) when
  //! sliding; at standstill the static friction balances the applied current up to +-Ks.
  //! `external` = current - friction, the part left for external forces. Non-finite inputs give
  //! 0 on both outputs for that joint and `non_finite_input`.
  [[nodiscard]] NumericStatus compensate(const Vector& current, const Vector& velocity,
                                         Vector& friction, Vector& external) const noexcept {
    NumericStatus status = NumericStatus::ok;
    for (int j = 0; j < N; ++j) {
      const Scalar i = current[j];
      const Scalar w = velocity[j];
      if (!std::isfinite(i) || !std::isfinite(w)) {
        friction[j] = 0;
        external[j] = 0;
        status = NumericStatus::non_finite_input;
        continue;
      }
      const Joint& c = joints_[static_cast<std::size_t>(j)];
      Scalar f;
      if (std::abs(w) <= options_.standstill_velocity) {
        f = std::clamp(i, -c.static_level, c.static_level);
      } else {
        f = c.viscous_gain * w + std::copysign(c.coulomb_level, w);
      }
      friction[j] = f;
      external[j] = i - f;
    }
    return status;
  }

  //! One tick of the 5.2.3 gate: a closed gate opens when |current| > level(velocity), an open
  //! one closes when |current| < release_fraction * level(velocity); `feedback` = estimate where
  //! open, else 0. A joint with a non-finite current, velocity or estimate is closed, its
  //! feedback is 0 and the result is `non_finite_input`; the other joints are unaffected.
  [[nodiscard]] NumericStatus update(const Vector& current, const Vector& velocity,
                                     const Vector& estimate, Vector& feedback) noexcept {
    NumericStatus status = NumericStatus::ok;
    for (int j = 0; j < N; ++j) {
      const auto js = static_cast<std::size_t>(j);
      if (!std::isfinite(current[j]) || !std::isfinite(velocity[j]) ||
          !std::isfinite(estimate[j])) {
        open_[js] = false;
        feedback[j] = 0;
        status = NumericStatus::non_finite_input;
        continue;
      }
      const Scalar magnitude = std::abs(current[j]);
      const Scalar level = level_of(j, velocity[j]);
      if (open_[js]) {
        open_[js] = !(magnitude < options_.release_fraction * level);
      } else {
        open_[js] = magnitude > level;
      }
      feedback[j] = open_[js] ? estimate[j] : Scalar(0);
    }
    return status;
  }

 private:
  Scalar level_of(int j, Scalar w) const noexcept {
    const Joint& c = joints_[static_cast<std::size_t>(j)];
    const Scalar speed = std::abs(w);
    return speed <= options_.standstill_velocity ? c.static_level
                                                 : c.coulomb_level + c.viscous_gain * speed;
  }

  static void check_level(Scalar value, std::size_t j, std::string_view field) {
    if (!std::isfinite(value) || value < 0) {
      ENDOHAPTICS_THROW(Error("FrictionModel: joint " + std::to_string(j) + " " +
                              std::string(field) + " must be finite and >= 0, got " +
                              endohaptics::detail::format_number(value)));
    }
  }

  Joints joints_;
  Options options_;
  GateState open_{};
};

//! The 2016 simplified model with table 5.2 levels, joints in the order of friction_2016::Joint
//! (roll, pitch, yaw, clamp). Throws Error on invalid `options`.
template <typename Scalar = double>
[[nodiscard]] FrictionModel<4, Scalar> endowrist_2016_friction(
    const FrictionOptions<Scalar>& options = {}) {
  auto cast = [](const JointFriction<double>& j) {
    return JointFriction<Scalar>{static_cast<Scalar>(j.static_level),
                                 static_cast<Scalar>(j.coulomb_level),
                                 static_cast<Scalar>(j.viscous_gain)};
  };
  return FrictionModel<4, Scalar>({cast(friction_2016::roll), cast(friction_2016::pitch),
                                   cast(friction_2016::yaw), cast(friction_2016::clamp)},
                                  options);
}

}  // namespace endohaptics::model
