//! @file
//! The force models the bridge runs (the real-time types; loading them from files is
//! files/clamp_model_file.hpp): every motor's slot is a BridgeJointModel, which holds the
//! motor's 2016 appendix C model (roll, pitch, or the yaw Hammerstein-Wiener type for the clamps),
//! an identified Hammerstein-Wiener model, one of the joint force models (StallHold,
//! PushLoadObserver, BidirectionalLoadObserver) or the 2016 code's clamp estimator. Forces in N
//! (roll: N m with its 2016 model, N with an identified one, as the model was fitted).
#pragma once

#include <cmath>
#include <cstddef>
#include <limits>
#include <optional>
#include <utility>

#include "endohaptics/estimation/any_joint_force_model.hpp"
#include "endohaptics/estimation/bidirectional_load_observer.hpp"
#include "endohaptics/estimation/clamp_2016_as_run.hpp"
#include "endohaptics/estimation/force_estimator.hpp"
#include "endohaptics/estimation/force_models_2016.hpp"
#include "endohaptics/estimation/push_load_observer.hpp"
#include "endohaptics/estimation/stall_hold.hpp"
#include "endohaptics/model/friction_model.hpp"
#include "endohaptics/model/static_nonlinearity.hpp"
#include "endohaptics/model/stop_operators.hpp"

namespace endohaptics::estimation {

//! A Hammerstein-Wiener force model identified from data (endohaptics-identify; 2 inputs: the
//! reported current, A, and velocity, rad/s; 1 output, N) run in the appendix C yaw model's type
//! (6 states; a lower order embedded exactly, model::embed_states). A type of its own so that the
//! bridge tells it from the 2016 yaw preset: it runs without the 2016 gate and unit scale
//! (bridge_estimator_settings).
//!
//! Optionally the current passes a play (backlash) operator of half width `current_play` A before
//! the model (files::ModelFile::current_play): z = min(max(z, i - w), i + w), starting at 0. It is
//! the joint's static friction seen from the motor: a joint pressed into an object sticks while
//! the tendon's torque stays within the static-friction band of the contact's, so on unloading
//! the current falls by up to 2 w while the force stays, and on loading the current leads the
//! force by w. The play's output and its sliding state are held in the state's last two entries.
//!
//! A joint whose Coulomb friction is well below its static friction (the emulated roll: K_c 0.065
//! against K_s 0.13 A) slides at a narrower band than it sticks at: then the play is
//! model::friction_play, stuck within `current_play` and sliding at `current_play_slide` plus the
//! viscous friction's current `current_play_viscous` v (v the model's velocity input; the
//! coefficient in the reported signals' signs, so -F_mu for a rig that reports the current
//! negated). Sliding in free motion the played output then stays at 0 instead of riding the
//! velocity's share; and the joint counts as sliding while that viscous current has the slide's
//! sign (it moves), not only while the current keeps pulling: a current that wavers while the
//! joint slides out of a contact does not stick the play at a stale load.
template <typename Scalar = double>
class IdentifiedHammersteinWiener : public ClampModel2016<Scalar> {
 public:
  using Base = ClampModel2016<Scalar>;                   //!< the yaw type it runs in
  using Signals = typename Base::Signals;                //!< one joint's signals for one tick
  using Threshold = model::FreeMotionThreshold<Scalar>;  //!< on its output
  //! The model's state, then the play's output (A) and sliding state (-1, 0, +1).
  using State = Eigen::Matrix<Scalar, Base::State::RowsAtCompileTime + 2, 1>;

  //! `model` (of the yaw type), its output through `threshold` (the model file's
  //! free_motion_threshold; the default is none), its current through a play of half width
  //! `current_play` A (0: none), sliding at `current_play_slide` A (none: the same, a plain
  //! play) on the current less `current_play_viscous` times the velocity. Throws Error unless
  //! the three pass model::check_friction_play.
  explicit IdentifiedHammersteinWiener(typename Base::ModelType model, Threshold threshold = {},
                                       Scalar current_play = Scalar(0),
                                       std::optional<Scalar> current_play_slide = std::nullopt,
                                       Scalar current_play_viscous = Scalar(0))
      : Base(std::move(model)),
        threshold_(threshold),
        play_(current_play),
        slide_(model::friction_play_slide(play_, current_play_slide)),
        viscous_(current_play_viscous) {
    model::check_friction_play(static_cast<double>(play_),
                               current_play_slide
                                   ? std::optional<double>(static_cast<double>(*current_play_slide))
                                   : std::nullopt,
                               static_cast<double>(viscous_), "IdentifiedHammersteinWiener");
  }

  //! The model's force through the free-motion threshold.
  [[nodiscard]] Scalar force(const Signals& s) const noexcept {
    return threshold_.apply(Base::force(played(s)));
  }
  //! One model period on the played current (all-or-nothing).
  [[nodiscard]] model::NumericStatus advance(const Signals& s) noexcept {
    Scalar sliding = sliding_;
    const Signals p = played(s, sliding);
    const model::NumericStatus status = Base::advance(p);
    if (status == model::NumericStatus::ok) {
      z_ = p.current;
      sliding_ = sliding;
    }
    return status;
  }
  //! The model's state, then the play's output.
  [[nodiscard]] State state() const noexcept {
    State x;
    x.template head<Base::State::RowsAtCompileTime>() = Base::state();
    x[State::RowsAtCompileTime - 2] = z_;
    x[State::RowsAtCompileTime - 1] = sliding_;
    return x;
  }
  //! Sets the model's state and the play's output from `x` (what state() returned).
  void reset(const State& x) noexcept {
    Base::reset(typename Base::State(x.template head<Base::State::RowsAtCompileTime>()));
    z_ = x[State::RowsAtCompileTime - 2];
    sliding_ = x[State::RowsAtCompileTime - 1];
  }
  //! Zero state, the play centred and stuck.
  void reset() noexcept { reset(State::Zero()); }
  //! The free-motion threshold.
  [[nodiscard]] const Threshold& threshold() const noexcept { return threshold_; }
  //! The play's half width, A (0: none).
  [[nodiscard]] Scalar current_play() const noexcept { return play_; }
  //! The play's half width while the joint slides, A (current_play() for a plain play).
  [[nodiscard]] Scalar current_play_slide() const noexcept { return slide_; }
  //! The viscous coefficient taken off the play's input, A per (rad/s) (0: none).
  [[nodiscard]] Scalar current_play_viscous() const noexcept { return viscous_; }

 private:
  //! `s` with the current replaced by the play's output for it (a NaN current stays NaN, so
  //! advance refuses it and the play keeps its output); `sliding` the sliding state after it.
  [[nodiscard]] Signals played(const Signals& s, Scalar& sliding) const noexcept {
    if (play_ == Scalar(0)) return s;
    Signals p = s;
    if (!std::isfinite(s.current)) return p;
    if (slide_ == play_ && viscous_ == Scalar(0)) {  // a plain play
      p.current = model::play(z_, s.current, play_);
      return p;
    }
    const Scalar viscous = viscous_ * s.velocity;
    if (!std::isfinite(viscous)) {  // a NaN velocity, or one so large the product overflows:
      p.current = std::numeric_limits<Scalar>::quiet_NaN();  // advance refuses it, z_ stays
      return p;
    }
    p.current = model::friction_play(z_, sliding, s.current, play_, slide_, viscous);
    return p;
  }
  [[nodiscard]] Signals played(const Signals& s) const noexcept {
    Scalar sliding = sliding_;
    return played(s, sliding);
  }

  Threshold threshold_;
  Scalar play_ = Scalar(0);
  Scalar slide_ = Scalar(0);
  Scalar viscous_ = Scalar(0);
  Scalar z_ = Scalar(0);
  Scalar sliding_ = Scalar(0);
};

//! The force model of one motor slot of the bridge, whichever kind its model file or preset
//! holds: the 2016 appendix C models (ClampModel2016 for a clamp, RollModel2016, PitchModel2016),
//! IdentifiedHammersteinWiener, StallHold, PushLoadObserver, BidirectionalLoadObserver, or the
//! preset "clamp2016-as-run" (Clamp2016AsRun, estimation/clamp_presets.hpp): an
//! AnyJointForceModel of the eight (a JointForceModel: noexcept, allocation-free; its State the
//! model's padded to the largest, the as-run filter's 42 numbers; reset() the model's own start
//! state).
using BridgeJointModel =
    AnyJointForceModel<ClampModel2016<double>, IdentifiedHammersteinWiener<double>,
                       StallHold<double>, PushLoadObserver<double>,
                       BidirectionalLoadObserver<double>, Clamp2016AsRun<double>,
                       RollModel2016<double>, PitchModel2016<double>>;

static_assert(JointForceModel<BridgeJointModel>);

//! The models the bridge's ForceEstimator runs: a BridgeJointModel per joint.
using BridgeForceModels = ForceModels<BridgeJointModel, BridgeJointModel, BridgeJointModel>;
//! The bridge's ForceEstimator: the 2016 rates (rate::Decimate) and BridgeForceModels.
using BridgeForceEstimator =
    ForceEstimator<rate::Decimate, BridgeJointModel, BridgeJointModel, BridgeJointModel>;

//! States of the bridge's Hammerstein-Wiener types (the appendix C yaw model's 6); a model file
//! of lower order is embedded in them (model::embed_states).
inline constexpr int bridge_clamp_states = 6;

//! The 2016 models (models_2016), with `clamp` for both clamps when given.
[[nodiscard]] inline BridgeForceModels bridge_force_models(
    const std::optional<BridgeJointModel>& clamp = std::nullopt) {
  const auto m2016 = models_2016<double>();
  BridgeForceModels models{BridgeJointModel(m2016.roll), BridgeJointModel(m2016.pitch),
                           BridgeJointModel(m2016.clamp1), BridgeJointModel(m2016.clamp2)};
  if (clamp) {
    models.clamp1 = *clamp;
    models.clamp2 = *clamp;
  }
  return models;
}

//! True when `model` holds `joint`'s own appendix C model (the 2016 preset of that joint).
[[nodiscard]] inline bool holds_2016_model(Motor joint, const BridgeJointModel& model) noexcept {
  switch (joint) {
    case Motor::roll:
      return model.get<RollModel2016<double>>() != nullptr;
    case Motor::pitch:
      return model.get<PitchModel2016<double>>() != nullptr;
    case Motor::clamp1:
    case Motor::clamp2:
      return model.get<ClampModel2016<double>>() != nullptr;
  }
  return false;
}

//! The estimator settings the bridge runs with `models`: `settings` for a joint that runs its
//! 2016 appendix C model; for a joint that runs any other model (identified, a joint model, the
//! 2016 code as run) the 5.2.3 friction gate is opened (level 0), the unit scale is 1 and the
//! output limit is the clamps' (a force, N). The gate, the pitch model's gram-force unit and the
//! roll model's 0.084 N m limit belong to the appendix C models: a model fitted to data holds its
//! own friction (dead zones, the push regime) and gives its output in the unit of the force it
//! was fitted to, and the gate would drop the force such a model holds while the jaw is stalled
//! against an object and the current has relaxed below the friction level.
[[nodiscard]] inline ForceEstimatorSettings<double> bridge_estimator_settings(
    ForceEstimatorSettings<double> settings, const BridgeForceModels& models) {
  const std::pair<Motor, const BridgeJointModel*> joints[] = {{Motor::roll, &models.roll},
                                                              {Motor::pitch, &models.pitch},
                                                              {Motor::clamp1, &models.clamp1},
                                                              {Motor::clamp2, &models.clamp2}};
  for (const auto& [joint, model] : joints) {
    if (!holds_2016_model(joint, *model)) {
      const auto j = static_cast<std::size_t>(joint);
      settings.friction[j] = model::JointFriction<double>::simplified(0.0);
      settings.unit_scale[static_cast<Eigen::Index>(j)] = 1.0;
      settings.output_limit[static_cast<Eigen::Index>(j)] =
          settings.output_limit[static_cast<Eigen::Index>(Motor::clamp1)];
    }
  }
  return settings;
}

}  // namespace endohaptics::estimation
