//! @file
//! StopOperators: N stop (elastic-play) operators of the Prandtl-Ishlinskii hysteresis model
//! (Krasnosel'skii and Pokrovskii, "Systems with Hysteresis", 1989; Kuhnen, "Modeling,
//! identification and compensation of complex hysteretic nonlinearities", 2003): for a threshold
//! r the play output z follows z = min(max(z, q - r), q + r) and the normalised stop output is
//! s = (q - z) / r in [-1, 1]: rate-independent, it depends only on the travel since the last
//! reversals, not on the absolute position. Units: q in rad (any unit, thresholds in the same).
#pragma once

#include <Eigen/Core>
#include <cmath>
#include <optional>
#include <string>
#include <string_view>
#include <type_traits>

#include "endohaptics/core/error.hpp"
#include "endohaptics/model/joint_model_bounds.hpp"

namespace endohaptics::model {

//! The play (backlash) operator of half width `r` >= 0, one sample: its output z follows the
//! input q only once q is more than r away, z_k = min(max(z_{k-1}, q_k - r), q_k + r). Each of
//! StopOperators' thresholds runs one; identified force models run one on the motor current
//! (files::ModelFile::current_play, estimation::IdentifiedHammersteinWiener,
//! identification::played_input). Precondition: q finite.
template <typename Scalar>
[[nodiscard]] inline Scalar play(Scalar z, Scalar q, Scalar r) noexcept {
  return std::fmin(std::fmax(z, q - r), q + r);
}

//! The play of a joint whose friction sticks at `stick` and slides at `slide` (Karnopp's
//! stick-slip friction seen from the motor current q: static K_s, Coulomb K_c <= K_s, viscous
//! `viscous`, the current the viscous friction would take at the measured velocity), one sample.
//! z is the current the joint's load takes, `sliding` its state: 0 stuck, +1 or -1 sliding that
//! way. Stuck, z holds until q is more than `stick` away (the joint does not move, so no viscous
//! term: a motor velocity then is the tendon winding up); then the joint breaks away, and while it
//! slides the load takes all but the Coulomb and viscous friction, z = q - viscous - sliding *
//! slide. It slides as long as q - viscous keeps pulling that way or `viscous` has the slide's
//! sign (the joint moves that way); when neither holds, it sticks again and only `stick` frees
//! it. With slide == stick and viscous 0 it is play(z, q, stick). Precondition: q and viscous
//! finite, 0 <= slide <= stick.
template <typename Scalar>
[[nodiscard]] inline Scalar friction_play(Scalar z, Scalar& sliding, Scalar q, Scalar stick,
                                          Scalar slide, Scalar viscous = Scalar(0)) noexcept {
  const Scalar load = q - viscous;  // what the load and the Coulomb friction take, sliding
  if (sliding != Scalar(0) && (sliding * (load - z) >= slide || sliding * viscous > Scalar(0))) {
    return load - sliding * slide;
  }
  sliding = Scalar(0);
  if (q - z > stick) {
    sliding = Scalar(1);
    return load - slide;
  }
  if (z - q > stick) {
    sliding = Scalar(-1);
    return load + slide;
  }
  return z;
}

//! The sliding half width a friction play runs with: `slide` when given, else the play's own
//! half width `stick` (no Coulomb drop: friction_play is then play()). The one place that default
//! is decided: identify's request and report, the model comparison and the bridge's force model
//! (estimation::IdentifiedHammersteinWiener) call it.
template <typename Scalar>
[[nodiscard]] constexpr Scalar friction_play_slide(
    Scalar stick, std::type_identity_t<std::optional<Scalar>> slide) noexcept {
  return slide ? *slide : stick;
}

//! The names a friction play's three constants go by where they are read (a model file's keys by
//! default; identify's options; a constructor's parameters), for check_friction_play's messages.
struct FrictionPlayNames {
  std::string_view play = "current_play";             //!< the static half width K_s
  std::string_view slide = "current_play_slide";      //!< the sliding half width K_c
  std::string_view viscous = "current_play_viscous";  //!< the viscous coefficient
};

//! The one rule for a friction play's constants, checked by the model-file loader, identify's
//! request and estimation::IdentifiedHammersteinWiener: the half width `play` in [0,
//! max_joint_model_parameter] (A); the sliding half width `slide` (none: a plain play, the
//! play's own) in [0, play]; the viscous coefficient finite and at most
//! max_joint_model_parameter in size; a slide or a viscous term only with a play. Configuration
//! time: throws Error naming the rule, after "`where`: " when `where` is not empty.
inline void check_friction_play(double play, std::optional<double> slide, double viscous,
                                std::string_view where, const FrictionPlayNames& names = {}) {
  using endohaptics::detail::format_number;
  const auto fail = [&](const std::string& what) {
    ENDOHAPTICS_THROW(Error(where.empty() ? what : std::string(where) + ": " + what));
  };
  const std::string p(names.play), s(names.slide), v(names.viscous);
  if (!(play >= 0.0 && play <= max_joint_model_parameter)) {
    fail(p + " must be in [0, " + format_number(max_joint_model_parameter) +
         "] (input 0's units), got " + format_number(play));
  }
  if (slide && !(*slide >= 0.0 && *slide <= play)) {
    fail(s + " must be in [0, " + p + " = " + format_number(play) + "], got " +
         format_number(*slide));
  }
  if (!(std::fabs(viscous) <= max_joint_model_parameter)) {
    fail(v + " must be finite, at most " + format_number(max_joint_model_parameter) +
         " in size, got " + format_number(viscous));
  }
  if (play == 0.0 && (slide || viscous != 0.0)) fail(s + " and " + v + " need a " + p);
}

//! N stop operators with increasing thresholds (see the file comment). Before the first motion
//! the history is unknown: every output stays 0 until the position has travelled `start_travel`
//! from where it started; then the operators start as if the motion before the start had run the
//! other way (each saturated at minus the sign of the first move: a tool that starts at rest at
//! one end of its stroke, where the previous motion ended). The state is a plain vector so that a
//! model can keep it inside its own; step() is noexcept and allocation-free.
template <typename Scalar, int N>
class StopOperators {
  static_assert(N >= 1, "StopOperators needs at least one threshold");

 public:
  using Thresholds = Eigen::Matrix<Scalar, N, 1>;  //!< r_1 < ... < r_N, > 0
  using Values = Eigen::Matrix<Scalar, N, 1>;      //!< s_1 ... s_N, each in [-1, 1]
  //! (play outputs z_1 ... z_N, start position, phase: 0 no sample yet, 1 waiting for the first
  //! travel, 2 running)
  using State = Eigen::Matrix<Scalar, N + 2, 1>;

  //! Throws Error unless the thresholds are finite, > 0 and strictly increasing and
  //! `start_travel` is finite and >= 0.
  StopOperators(const Thresholds& thresholds, Scalar start_travel)
      : r_(thresholds), inverse_(thresholds.cwiseInverse()), start_travel_(start_travel) {
    validate(thresholds, start_travel);
  }

  //! The checks of the constructor, for parameter structs that hold the values.
  static void validate(const Thresholds& r, Scalar start_travel) {
    for (int j = 0; j < N; ++j) {
      const bool ok = std::isfinite(r[j]) && r[j] > 0 && (j == 0 || r[j] > r[j - 1]);
      if (!ok) {
        ENDOHAPTICS_THROW(Error("StopOperators: threshold " + std::to_string(j) +
                                " must be finite, > 0 and above the one before, got " +
                                endohaptics::detail::format_number(r[j])));
      }
    }
    if (!(std::isfinite(start_travel) && start_travel >= 0)) {
      ENDOHAPTICS_THROW(Error("StopOperators: start_travel must be finite and >= 0, got " +
                              endohaptics::detail::format_number(start_travel)));
    }
  }

  [[nodiscard]] const Thresholds& thresholds() const noexcept { return r_; }    //!< as given
  [[nodiscard]] Scalar start_travel() const noexcept { return start_travel_; }  //!< as given

  //! The state before any sample.
  [[nodiscard]] static State initial_state() noexcept { return State::Zero(); }

  //! One position sample `q`: updates `x` and writes the outputs to `s`. Precondition: q finite.
  void step(State& x, Scalar q, Values& s) const noexcept {
    if (x[N + 1] == Scalar(0)) {  // first sample: remember where the motion starts
      x[N] = q;
      x[N + 1] = Scalar(1);
    }
    if (x[N + 1] == Scalar(1)) {
      const Scalar travel = q - x[N];
      if (std::fabs(travel) < start_travel_ || travel == Scalar(0)) {
        s.setZero();
        return;
      }
      // Saturated at -sign(first move) at the start position: z_j = start + sign r_j.
      const Scalar sign = travel > 0 ? Scalar(1) : Scalar(-1);
      for (int j = 0; j < N; ++j) x[j] = x[N] + sign * r_[j];
      x[N + 1] = Scalar(2);
    }
    for (int j = 0; j < N; ++j) {
      x[j] = play(x[j], q, r_[j]);
      s[j] = (q - x[j]) * inverse_[j];
    }
  }

  //! The outputs of state `x` without a new sample (0 before the first travel).
  [[nodiscard]] Values values(const State& x, Scalar q) const noexcept {
    Values s = Values::Zero();
    if (x[N + 1] != Scalar(2)) return s;
    for (int j = 0; j < N; ++j) s[j] = (q - x[j]) * inverse_[j];
    return s;
  }

 private:
  Thresholds r_;
  Thresholds inverse_;  // 1 / r_j: the outputs multiply (a division costs several multiplies)
  Scalar start_travel_;
};

}  // namespace endohaptics::model
