//! @file
//! The press-and-hold sweep of docs/passivity.md over sim::ClosedLoop: its scenarios (round trip
//! in ms x loss x contact, without passivity or with TDPA), one run analysed (analyze_press), and
//! the criteria the sweep judges by: with TDPA passive (energy above -0.015 J), decaying, within
//! 5 mrad of drift, below the loop's 3 N and still felt (0.4 N); without, stable or why not.
//! Simulation time; allocates (the samples), not for a tick.
#pragma once

#include <array>
#include <chrono>
#include <memory>
#include <string>
#include <utility>
#include <vector>

#include "endohaptics/sim/closed_loop.hpp"
#include "endohaptics/teleop/passivity.hpp"

namespace endohaptics::sim {

//! The sweep's criteria.
struct PressCriteria {
  //! J: the observer may dip into the operator-side reserve (PassivityConfig::energy_reserve,
  //! 0.01 J) and by the robot port's last steps; never further than this.
  double epsilon = 0.015;
  //! rad of clamp 1 the robot-side controller may still hold back after the hold (0.9 mm of
  //! stylus).
  double max_drift = 0.005;
  double force_limit = 3.0;  //!< N, the loop's stylus force limit (never reached with TDPA)
  double min_hold = 0.4;     //!< N, the contact still felt at the end of the hold
};

//! Seconds simulated without passivity: the oscillation 1 s after the first peak is seen.
inline constexpr double press_seconds_without = 4.0;
//! Seconds simulated with TDPA: a 10 s hold after the first contact.
inline constexpr double press_seconds_with = 11.5;
//! Round trips of the sweep's table, ms.
inline constexpr std::array<int, 5> press_round_trips_ms{0, 20, 50, 100, 200};
//! Round trips of the transparency table, ms.
inline constexpr std::array<int, 8> transparency_round_trips_ms{0,   50,  100, 200,
                                                                300, 500, 700, 1000};

//! One scenario: `round_trip_ms` ms round trip, `loss` per direction, the contact and the
//! passivity mode (observe: the loop renders what it renders with the layer off, energy visible),
//! the network's random seed 7 (the documented table's).
[[nodiscard]] inline ClosedLoopConfig press_scenario(int round_trip_ms, double loss,
                                                     ContactKind contact,
                                                     teleop::PassivityMode mode) {
  ClosedLoopConfig c;
  c.round_trip = std::chrono::milliseconds(round_trip_ms);
  c.loss = loss;
  c.seed = 7;
  c.contact = contact;
  c.passivity.mode = mode;
  return c;
}

//! Runs `config` for `seconds` of simulated time and analyses the press; the samples are left in
//! `*keep` when given.
[[nodiscard]] inline PressReport run_press(const ClosedLoopConfig& config, double seconds,
                                           std::vector<ClosedLoopSample>* keep = nullptr) {
  auto loop = std::make_unique<ClosedLoop>(config);
  std::vector<ClosedLoopSample> samples;
  loop->run(seconds, samples);
  const PressReport report = analyze_press(*loop, samples);
  if (keep != nullptr) *keep = std::move(samples);
  return report;
}

//! A run without passivity: "stable", or "UNSTABLE (...)" naming what failed: no decay, energy
//! generated (below -criteria.epsilon), the force limit reached.
[[nodiscard]] inline std::string press_verdict_without(const PressReport& r,
                                                       const PressCriteria& criteria = {}) {
  std::string why;
  const auto add = [&why](const char* what) {
    why += (why.empty() ? "" : ", ") + std::string(what);
  };
  if (!r.decays()) add("no decay");
  if (r.min_energy < -criteria.epsilon) add("energy generated");
  if (r.max_force >= criteria.force_limit - 1e-9) add("force limit");
  return why.empty() ? "stable" : "UNSTABLE (" + why + ")";
}

//! A run with TDPA meets the criteria: contact, passive, decaying, drift and force bounded, the
//! contact still felt.
[[nodiscard]] inline bool press_meets_criteria(const PressReport& r,
                                               const PressCriteria& criteria = {}) {
  return r.contact && r.min_energy > -criteria.epsilon && r.decays() &&
         r.drift < criteria.max_drift && r.max_force < criteria.force_limit &&
         r.hold_force > criteria.min_hold;
}

}  // namespace endohaptics::sim
