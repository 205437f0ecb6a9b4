//! @file
//! The force models the bridge runs (the real-time types; loading them from files is
//! files/clamp_model_file.hpp): the 2016 roll and pitch models and, for both clamps, a
//! ClampForceModel that holds the appendix C yaw Hammerstein-Wiener type or one of the joint
//! force models (StallHold, PushLoadObserver, BidirectionalLoadObserver). Forces in N.
#pragma once

#include <cstddef>
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

namespace endohaptics::estimation {

//! The clamp model the bridge runs, whichever kind the model file holds: the appendix C yaw
//! Hammerstein-Wiener type (ClampModel2016, also identified "hammerstein_wiener" files of 6
//! states, 2 inputs, 1 output), StallHold, PushLoadObserver or BidirectionalLoadObserver, or the
//! preset "clamp2016-as-run" (Clamp2016AsRun, estimation/clamp_presets.hpp), as an
//! AnyJointForceModel of the five (a JointForceModel: noexcept, allocation-free, its State the
//! model's padded to the as-run filter's 42 numbers; reset() the model's own start state).
using ClampForceModel =
    AnyJointForceModel<ClampModel2016<double>, StallHold<double>, PushLoadObserver<double>,
                       BidirectionalLoadObserver<double>, Clamp2016AsRun<double>>;

static_assert(JointForceModel<ClampForceModel>);

//! The models the bridge's ForceEstimator runs: the 2016 roll and pitch models, ClampForceModel
//! for both clamps.
using BridgeForceModels =
    ForceModels<RollModel2016<double>, PitchModel2016<double>, ClampForceModel>;
//! The bridge's ForceEstimator: the 2016 rates (rate::Decimate) and BridgeForceModels.
using BridgeForceEstimator =
    ForceEstimator<rate::Decimate, RollModel2016<double>, PitchModel2016<double>, ClampForceModel>;

//! States of the bridge's Hammerstein-Wiener clamp model (ClampModel2016: the appendix C yaw
//! model's 6); a clamp model file of lower order is embedded in them (model::embed_states).
inline constexpr int bridge_clamp_states = 6;

//! The 2016 models (models_2016), with `clamp` for both clamps when given.
[[nodiscard]] inline BridgeForceModels bridge_force_models(
    const std::optional<ClampForceModel>& clamp = std::nullopt) {
  const auto m2016 = models_2016<double>();
  BridgeForceModels models{m2016.roll, m2016.pitch, ClampForceModel(m2016.clamp1),
                           ClampForceModel(m2016.clamp2)};
  if (clamp) {
    models.clamp1 = *clamp;
    models.clamp2 = *clamp;
  }
  return models;
}

//! The estimator settings the bridge runs with `models`: `settings`, except that the 5.2.3
//! friction gate of a clamp is opened (level 0) when its model is a joint model (stall_hold, the
//! observers, the 2016 code as run): those models hold their own friction (the dead zone, the
//! push regime), and the gate would drop the force they hold while the jaw is stalled against an
//! object and the current has relaxed below the friction level. Each clamp by its own model (a
//! model set may give the two clamps different kinds).
[[nodiscard]] inline ForceEstimatorSettings<double> bridge_estimator_settings(
    ForceEstimatorSettings<double> settings, const BridgeForceModels& models) {
  const std::pair<Motor, const ClampForceModel*> clamps[] = {{Motor::clamp1, &models.clamp1},
                                                             {Motor::clamp2, &models.clamp2}};
  for (const auto& [joint, clamp] : clamps) {
    if (clamp->index() != 0) {  // not the Hammerstein-Wiener kind
      settings.friction[static_cast<std::size_t>(joint)] =
          model::JointFriction<double>::simplified(0.0);
    }
  }
  return settings;
}

}  // namespace endohaptics::estimation
