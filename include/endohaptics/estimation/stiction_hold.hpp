//! @file
//! StictionHold: the stiction memory of ForceEstimator (Settings::stick_travel, stick_play,
//! stick_force) as a filter after any estimator, with one difference: the held force is kept
//! while the estimate falls *through zero*, not only while it falls on the same side. A joint
//! stuck in an object keeps its contact force until its motor has backed off through the static
//! friction band (and the play), whatever the model reads meanwhile; a current-and-velocity
//! model reads its backing-off motor and a current inside its input dead zone as zero or a
//! small force the other way (the passivity sweep's identified clamp model: the relaxed current
//! 0.158 A inside its 0.163 A dead zone, the estimate -0.016 N with 0.70 N of true contact and
//! the motor backed off 0.025 of the 0.031 rad stuck travel; docs/passivity.md). ForceEstimator's
//! memory lets go there. Per joint, fixed size, noexcept, no allocation.
#pragma once

#include <Eigen/Core>
#include <cmath>
#include <string>

#include "endohaptics/core/error.hpp"
#include "endohaptics/estimation/force_estimator.hpp"

namespace endohaptics::estimation {

//! The stiction memory holding through zero, per joint (index as the settings' vectors).
class StictionHold {
 public:
  using Vector = Eigen::Matrix<double, 4, 1>;  //!< one value per joint

  //! The memory's settings (ForceEstimatorSettings::stick_travel, stick_play, stick_force; a
  //! joint with stick_travel 0 passes its estimate on) and `contact_level`, N per joint: the
  //! estimate's error bound in free motion. A held force within it is no evidence of a contact
  //! and is held only while the estimate falls on the same side (ForceEstimator's rule): held
  //! through zero, a few hundredths of a newton of noise would block a real press the other
  //! way. Throws Error on a negative or non-finite value.
  explicit StictionHold(const ForceEstimatorSettings<double>& settings,
                        const Vector& contact_level = Vector::Zero())
      : travel_(checked(settings.stick_travel, "stick_travel")),
        play_(checked(settings.stick_play, "stick_play")),
        force_(checked(settings.stick_force, "stick_force")),
        contact_(checked(contact_level, "contact_level")) {}

  //! Joint `j`'s force after the memory: `f` this tick's estimate (N, signed), `position` the
  //! motor's reported position (rad). The external force pushes along sign(held), so the motor
  //! pressed along -sign(held) and backs off along +sign(held). While the estimate is below the
  //! held force along that sign (smaller, zero or, for a held force beyond the contact level,
  //! the other way) and the motor has backed off from where it last pressed by more than 0 and
  //! less than the stuck travel (plus the play while the held force is below stick_force), the
  //! held force is returned.
  [[nodiscard]] double apply(int j, double f, double position) noexcept {
    if (!(travel_[j] > 0.0)) return f;
    double& held = held_[j];
    double& anchor = anchor_[j];
    const double side = held > 0.0 ? 1.0 : -1.0;
    const bool contact = std::fabs(held) > contact_[j];
    if (held != 0.0 && f * side < std::fabs(held) && (contact || f * side >= 0.0)) {
      const double travel = travel_[j] + (std::fabs(held) < force_[j] ? play_[j] : 0.0);
      const double backed_off = side * (position - anchor);
      if (backed_off > 0.0 && backed_off < travel) return held;  // the joint is still stuck
    }
    held = f;
    anchor = position;
    return f;
  }

  //! Forgets what it held (the link came back).
  void reset() noexcept {
    held_.setZero();
    anchor_.setZero();
  }

 private:
  static Vector checked(const Vector& v, const char* name) {
    for (int j = 0; j < 4; ++j) {
      if (!std::isfinite(v[j]) || v[j] < 0.0) {
        ENDOHAPTICS_THROW(Error(std::string("StictionHold: ") + name + "[" + std::to_string(j) +
                                "] must be finite and >= 0, got " +
                                endohaptics::detail::format_number(v[j])));
      }
    }
    return v;
  }

  Vector travel_;
  Vector play_;
  Vector force_;
  Vector contact_;
  Vector held_ = Vector::Zero();
  Vector anchor_ = Vector::Zero();
};

}  // namespace endohaptics::estimation
