//! @file
//! The bridge assembled from its configuration (files/bridge_config.hpp) and its loop settings
//! (--rate, --passivity, --max-answer-lag): the force models (the instrument's model set, or the
//! clamp model file, as estimation::BridgeJointModel), the 2016 force estimator paced at 1 kHz, the
//! cylindrical mapping (eqs. 5.8/5.9) and the TeleopLoop over any transport, device and clock.
//! Rates in Hz, times in s. Configuration time: throws endohaptics::Error; the loop it holds is the
//! real-time part.
#pragma once

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <optional>
#include <string>

#include "endohaptics/core/error.hpp"
#include "endohaptics/estimation/bridge_force_models.hpp"
#include "endohaptics/estimation/clamp_presets.hpp"
#include "endohaptics/estimation/paced_estimator.hpp"
#include "endohaptics/files/bridge_config.hpp"
#include "endohaptics/files/clamp_model_file.hpp"
#include "endohaptics/kinematics/cylindrical_mapper.hpp"
#include "endohaptics/teleop/passivity.hpp"
#include "endohaptics/teleop/safety.hpp"
#include "endohaptics/teleop/teleop_loop.hpp"
#include "endohaptics/workflow/command_line.hpp"

namespace endohaptics::workflow {

//! The bridge's loop settings from its command line.
struct BridgeLoopSettings {
  std::string rate = "1000";             //!< Hz, or "max" (no pause between ticks)
  bool tdpa = false;                     //!< time-domain passivity (docs/passivity.md)
  double passivity_round_trip_ms = 0.0;  //!< ms, the round trip TDPA books the robot port late
  int max_answer_lag = 0;                //!< v2: setpoints a state may answer behind the newest
};

//! Slowest --rate, Hz.
inline constexpr double bridge_min_rate_hz = 1.0;
//! Fastest --rate, Hz.
inline constexpr double bridge_max_rate_hz = 100000.0;
//! Period of the force estimator's grid (the 2016 models' rates divide it), s.
inline constexpr double bridge_estimator_period = 1e-3;

//! The longest an answer may take on this link, s: max_answer_lag + 1 periods of `tick_s`, plus
//! the activation allowance. It bounds the wait for a motor to report active, and it is the round
//! trip a v2 console asks the robot side to grant.
[[nodiscard]] inline double bridge_answer_allowance(int max_answer_lag, double tick_s) {
  return static_cast<double>(max_answer_lag + 1) * tick_s +
         teleop::SafetyConfig{}.activation_timeout;
}

//! The force models of `config` (files::bridge_config_force_models): the instrument's model set,
//! else the clamp model file or preset on both clamps, else the 2016 models. Throws Error naming
//! the file when they cannot be run.
[[nodiscard]] inline estimation::BridgeForceModels bridge_force_models(
    const files::BridgeConfig& config) {
  return files::bridge_config_force_models(config).models;
}

//! The estimator settings the bridge runs `models` with: config.estimator, the clamps' friction
//! gate opened for a joint model (estimation::bridge_estimator_settings), the 1 kHz grid.
[[nodiscard]] inline estimation::ForceEstimatorSettings<double> bridge_estimator_settings(
    const files::BridgeConfig& config, const estimation::BridgeForceModels& models) {
  auto settings = estimation::bridge_estimator_settings(config.estimator, models);
  settings.loop_period = bridge_estimator_period;
  return settings;
}

//! The loop's configuration: config.loop (safety, receive timeout) with the period of
//! `settings.rate`, an activation timeout that allows the answer lag, and TDPA when asked for
//! (booking only the joint force `unclipped_joint_force` the mapping renders unclipped). Throws
//! Error naming --rate when a lost link would take longer than
//! TeleopLoopConfig::max_watchdog_time to reach the safe state at that rate.
[[nodiscard]] inline teleop::TeleopLoopConfig bridge_loop_config(
    const files::BridgeConfig& config, const BridgeLoopSettings& settings,
    const estimation::MotorVector& unclipped_joint_force) {
  using std::chrono::nanoseconds;
  teleop::TeleopLoopConfig loop = config.loop;
  if (settings.rate == "max") {
    loop.period = nanoseconds(0);
  } else {
    const double hz = parse_number(settings.rate, "--rate", bridge_min_rate_hz, bridge_max_rate_hz);
    // A lost link reaches the safe state after max_consecutive_misses + 1 missed periods,
    // within TeleopLoopConfig::max_watchdog_time: that bounds the rate from below.
    const double watchdog_s =
        std::chrono::duration<double>(teleop::TeleopLoopConfig::max_watchdog_time).count();
    const int misses = loop.safety.max_consecutive_misses + 1;
    const double slowest = static_cast<double>(misses) / watchdog_s;
    if (hz < slowest) {
      char text[256];
      std::snprintf(text, sizeof text,
                    "at this rate %d missed periods (safety.max_consecutive_misses + 1) take "
                    "%.0f ms, longer than the %.0f ms a lost link may take to reach the safe "
                    "state; use --rate ",
                    misses, 1e3 * misses / hz, 1e3 * watchdog_s);
      ENDOHAPTICS_THROW(Error("--rate " + settings.rate + ": " + text +
                              endohaptics::detail::format_number(std::ceil(slowest)) +
                              " or more, or a lower safety.max_consecutive_misses"));
    }
    loop.period = nanoseconds(static_cast<std::int64_t>(1e9 / hz + 0.5));
  }
  // A motor enabled must be reported active within the activation timeout, or the robot is
  // not obeying; on a link whose answers lag (--max-answer-lag) that includes the round trip.
  const double tick_s = std::chrono::duration<double>(
                            loop.period.count() > 0 ? loop.period : std::chrono::milliseconds(1))
                            .count();
  loop.safety.activation_timeout =
      std::min(teleop::SafetyBounds::max_activation_timeout,
               std::max(loop.safety.activation_timeout,
                        bridge_answer_allowance(settings.max_answer_lag, tick_s)));
  if (settings.tdpa) {  // the robot port is booked one round trip late, in ticks
    loop.passivity.mode = teleop::PassivityMode::tdpa;
    const double period_ms = std::chrono::duration<double, std::milli>(loop.max_tick_dt()).count();
    loop.passivity.round_trip_ticks =
        static_cast<int>(std::lround(settings.passivity_round_trip_ms / period_ms));
    // Book only the joint force the mapping renders unclipped, so the observer's operator port
    // is the force felt.
    loop.passivity.force_limit = unclipped_joint_force;
  }
  return loop;
}

//! The bridge: force models, estimator (paced at 1 kHz on `clock`), mapping and TeleopLoop over
//! `transport` and `device`, assembled from `config` and `settings`. Owns all but the transport,
//! device and clock (which must outlive it); neither copied nor moved (the loop holds its
//! parts by address). Throws Error on a configuration the bridge cannot run.
template <typename Transport, typename Device, typename ClockT>
class BridgeAssembly {
 public:
  //! The estimator the loop calls: the bridge's ForceEstimator on a 1 kHz grid.
  using Paced = estimation::PacedEstimator<estimation::BridgeForceEstimator, ClockT>;
  //! The loop.
  using Loop =
      teleop::TeleopLoop<Transport, Device, Paced, kinematics::CylindricalMapper<>, ClockT>;

  //! Assembles the bridge; throws Error naming the option or the configuration's key.
  BridgeAssembly(Transport& transport, Device& device, ClockT& clock,
                 const files::BridgeConfig& config, const BridgeLoopSettings& settings)
      : models_(files::bridge_config_force_models(config)),
        estimator_(models_.models, bridge_estimator_settings(config, models_.models)),
        paced_(estimator_, clock,
               std::chrono::nanoseconds(
                   static_cast<std::int64_t>(bridge_estimator_period * 1e9 + 0.5))),
        mapper_(config.mapping),
        loop_(transport, device, paced_, mapper_, clock,
              bridge_loop_config(config, settings, mapper_.unclipped_joint_force())) {}

  BridgeAssembly(const BridgeAssembly&) = delete;
  BridgeAssembly& operator=(const BridgeAssembly&) = delete;

  [[nodiscard]] Loop& loop() noexcept { return loop_; }                 //!< the loop
  [[nodiscard]] const Loop& loop() const noexcept { return loop_; }     //!< the loop
  [[nodiscard]] const Paced& paced() const noexcept { return paced_; }  //!< its counters
  [[nodiscard]] const estimation::BridgeForceEstimator& estimator() const noexcept {
    return estimator_;
  }  //!< the force estimator
  [[nodiscard]] const kinematics::CylindricalMapper<>& mapper() const noexcept {
    return mapper_;
  }  //!< the mapping
  //! The force models it runs, as the bridge logs them ("instrument NAME (FILE): clamp1 ...").
  [[nodiscard]] const std::string& force_models_description() const noexcept {
    return models_.description;
  }

 private:
  files::BridgeModelSet models_;  // the models and their description (before estimator_)
  estimation::BridgeForceEstimator estimator_;
  Paced paced_;
  kinematics::CylindricalMapper<> mapper_;
  Loop loop_;
};

}  // namespace endohaptics::workflow
