//! @file
//! StictionHold: the stiction memory of a joint force estimate, per joint. A joint pressed into an
//! object sticks there by static friction while its motor backs off through the tendon's
//! static-friction band (and the play), so the motor's current relaxes while the contact force
//! stays; a current-and-velocity model reads that as a falling force. The memory holds the last
//! force while the estimate falls below it and the motor has backed off from where it last
//! pressed by more than 0 and less than the stuck travel (`stick_travel`, plus `stick_play`
//! while the held force is below `stick_force`): docs/models.md, "Stiction memory".
//!
//! ForceEstimator runs it after its gates (ForceEstimatorSettings::stick_*), by default holding
//! only while the estimate falls on the same side (a contact level of +infinity). With a finite
//! `contact_level` (ForceEstimatorSettings::stick_contact_level) a held force beyond it is also
//! held while the estimate falls *through zero*:
//! a model whose relaxed current lies inside its input dead zone reads a stuck joint as zero or
//! a small force the other way (the passivity sweep's dead-zone clamp model, docs/passivity.md,
//! "The stiction memory in the loop"). A held force within the level is no evidence of a contact
//! and is held on the same side only: held through zero, a few hundredths of a newton of noise
//! would block a real press the other way. Fixed size, noexcept, no allocation.
#pragma once

#include <Eigen/Core>
#include <cmath>
#include <limits>
#include <string>

#include "endohaptics/core/error.hpp"

namespace endohaptics::estimation {

//! The stiction memory of four joints (index: the tool joint, as the settings' vectors).
template <typename Scalar = double>
class StictionHold {
 public:
  using Vector = Eigen::Matrix<Scalar, 4, 1>;  //!< one value per joint

  //! Per joint: `travel` (rad, the stuck travel; 0: the joint's estimate passes unchanged),
  //! `play` (rad, added while the held force is below `force`), `force` (output units),
  //! `contact_level` (output units; +infinity, the default: hold on the same side only). Throws
  //! Error unless travel, play and force are finite and >= 0 and contact_level >= 0.
  StictionHold(const Vector& travel, const Vector& play, const Vector& force,
               const Vector& contact_level = no_contact_level())
      : travel_(checked(travel, "stick_travel", false)),
        play_(checked(play, "stick_play", false)),
        force_(checked(force, "stick_force", false)),
        contact_(checked(contact_level, "contact_level", true)) {}

  //! From any settings with `stick_travel`, `stick_play` and `stick_force`
  //! (ForceEstimatorSettings).
  template <typename Settings>
  requires requires(const Settings& s) {
    s.stick_travel;
    s.stick_play;
    s.stick_force;
  }
  explicit StictionHold(const Settings& s, const Vector& contact_level = no_contact_level())
      : StictionHold(s.stick_travel.template cast<Scalar>(), s.stick_play.template cast<Scalar>(),
                     s.stick_force.template cast<Scalar>(), contact_level) {}

  //! +infinity on every joint: hold only while the estimate falls on the same side.
  [[nodiscard]] static Vector no_contact_level() noexcept {
    return Vector::Constant(std::numeric_limits<Scalar>::infinity());
  }

  //! Joint `j`'s force after the memory: `f` this tick's estimate (signed), `position` the
  //! motor's (rad). The external force pushes along sign(held), so the motor pressed along
  //! -sign(held) and backs off along +sign(held). A fall with the motor not backed off is the
  //! model's own transient (a stop in free motion), not a tendon unloading in front of a stuck
  //! joint, and is followed.
  [[nodiscard]] Scalar apply(int j, Scalar f, Scalar position) noexcept {
    if (!(travel_[j] > Scalar(0))) return f;
    Scalar& held = held_[j];
    Scalar& anchor = anchor_[j];
    const Scalar side = held > Scalar(0) ? Scalar(1) : Scalar(-1);
    const bool contact = std::fabs(held) > contact_[j];
    if (held != Scalar(0) && f * side < std::fabs(held) && (contact || f * side >= Scalar(0))) {
      const Scalar travel = travel_[j] + (std::fabs(held) < force_[j] ? play_[j] : Scalar(0));
      const Scalar backed_off = side * (position - anchor);
      if (backed_off > Scalar(0) && backed_off < travel) return held;  // the joint is still stuck
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
  static Vector checked(const Vector& v, const char* name, bool infinite_ok) {
    for (int j = 0; j < 4; ++j) {
      if (!(v[j] >= Scalar(0)) || (!infinite_ok && !std::isfinite(v[j]))) {
        ENDOHAPTICS_THROW(Error(std::string("StictionHold: ") + name + "[" + std::to_string(j) +
                                "] must be " + (infinite_ok ? "" : "finite and ") + ">= 0, got " +
                                endohaptics::detail::format_number(static_cast<double>(v[j]))));
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
