//! @file
//! The clamp presets by name, defined once for every program that runs one: "yaw2016" (the
//! worksheet's appendix C yaw model with its table 5.2 dead zones and 5.2.3 friction gates) and
//! "clamp2016-as-run" (the estimator the 2016 code ran, Clamp2016AsRun, no gate). Each preset is
//! its force models and its estimator settings; run_clamp_preset runs one on a clamp's recorded
//! signals through the same ForceEstimator the bridge ticks (BridgeForceEstimator). Forces in N;
//! configuration time throws endohaptics::Error.
#pragma once

#include <Eigen/Core>
#include <concepts>
#include <cstdint>
#include <string>
#include <string_view>

#include "endohaptics/core/error.hpp"
#include "endohaptics/estimation/bridge_force_models.hpp"
#include "endohaptics/estimation/clamp_2016_as_run.hpp"
#include "endohaptics/estimation/force_estimator.hpp"
#include "endohaptics/estimation/force_models_2016.hpp"
#include "endohaptics/model/friction_model.hpp"

namespace endohaptics::estimation {

//! A clamp preset.
enum class ClampPreset : std::uint8_t {
  yaw2016,           //!< appendix C yaw HW model, table 5.2 dead zones, 5.2.3 gates
  clamp2016_as_run,  //!< the 2016 code's estimator (Clamp2016AsRun), no gate
};

//! The preset's name ("yaw2016", "clamp2016-as-run").
[[nodiscard]] constexpr std::string_view to_string(ClampPreset preset) noexcept {
  return preset == ClampPreset::yaw2016 ? "yaw2016" : "clamp2016-as-run";
}

//! The preset called `name`; throws Error listing the valid names for another.
[[nodiscard]] inline ClampPreset clamp_preset(std::string_view name) {
  for (const ClampPreset p : {ClampPreset::yaw2016, ClampPreset::clamp2016_as_run}) {
    if (name == to_string(p)) return p;
  }
  ENDOHAPTICS_THROW(
      Error("unknown clamp preset '" + std::string(name) + "' (valid: yaw2016, clamp2016-as-run)"));
}

//! The models of `preset` as the bridge runs them (BridgeForceModels, its BridgeJointModel on
//! both clamps). yaw2016: models_2016() (clamp 1 with the 0.21 A dead zone of table 5.2's yaw
//! row, clamp 2 with the 0.20 A of its clamp row). clamp2016-as-run: Clamp2016AsRun on both
//! clamps with input sign -1 (the code's clamp motor 1; the code's + on motor 4 is the mirrored
//! clamp 2 setpoint, which ForceEstimator's per-joint convention already carries).
[[nodiscard]] inline BridgeForceModels preset_force_models(ClampPreset preset) {
  if (preset == ClampPreset::clamp2016_as_run) {
    return bridge_force_models(BridgeJointModel(Clamp2016AsRun<double>{}));
  }
  return bridge_force_models();
}

//! The estimator settings of `preset` from `base` (the configuration's), the bridge's rule
//! (bridge_estimator_settings): yaw2016 keeps the table 5.2 gates; clamp2016-as-run opens both
//! clamps' gate (the 2016 code gated nothing: its Deadzone_switch calls are commented out; the
//! model holds the code's own 0.1 dead zone).
[[nodiscard]] inline ForceEstimatorSettings<double> preset_estimator_settings(
    ClampPreset preset, const ForceEstimatorSettings<double>& base = {}) {
  return bridge_estimator_settings(base, preset_force_models(preset));
}

//! The bridge's estimator with `preset` at `loop_period` s (the bridge: 1 ms), settings from
//! `base`.
[[nodiscard]] inline BridgeForceEstimator preset_force_estimator(
    ClampPreset preset, double loop_period, ForceEstimatorSettings<double> base = {}) {
  base.loop_period = loop_period;
  return BridgeForceEstimator(preset_force_models(preset), preset_estimator_settings(preset, base));
}

//! Runs `preset` on one clamp's recorded signals, sampled every `period` s (a multiple of 1 ms
//! dividing 0.02 s, or 0.02 s itself): for each k, signals(k) goes to clamp 1 (the other joints
//! read zeros) of preset_force_estimator(preset, period), and y[k] is the clamp 1 force it
//! gives, N. Returns the first failing sample's status; the outputs from it on are not written.
template <typename SignalsAt>
requires std::invocable<SignalsAt&, Eigen::Index>
[[nodiscard]] NumericStatus run_clamp_preset(ClampPreset preset, double period, SignalsAt&& signals,
                                             Eigen::Ref<Eigen::VectorXd> y) {
  BridgeForceEstimator estimator = preset_force_estimator(preset, period);
  const auto motor = static_cast<Eigen::Index>(Motor::clamp1);  // default motor_order
  typename BridgeForceEstimator::Input in;
  typename BridgeForceEstimator::Forces f;
  for (Eigen::Index k = 0; k < y.size(); ++k) {
    const JointSignals<double> s = signals(k);
    in.position[motor] = s.position;
    in.velocity[motor] = s.velocity;
    in.current[motor] = s.current;
    in.setpoint[motor] = s.setpoint;
    const NumericStatus status = estimator.step(in, f);
    if (status != NumericStatus::ok) return status;
    y[k] = f[static_cast<Eigen::Index>(Motor::clamp1)];
  }
  return NumericStatus::ok;
}

}  // namespace endohaptics::estimation
