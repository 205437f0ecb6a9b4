// What endohaptics-passivity-sweep prints: the sweep's table, the transparency table and one
// run's trace (CSV), over the library's scenarios and criteria (sim/passivity_sweep.hpp).
#pragma once

#include <fmt/format.h>

#include <algorithm>
#include <cstdio>
#include <endohaptics/sim/passivity_sweep.hpp>
#include <endohaptics/workflow/command_line.hpp>
#include <optional>
#include <string>
#include <utility>
#include <vector>

namespace sweep_print {

namespace sim = endohaptics::sim;
namespace tp = endohaptics::teleop;

//! Where the force comes from: the source and, for identified, the clamp model.
struct Source {
  sim::ForceSource source = sim::ForceSource::sensor;  //!< what is fed back
  std::optional<sim::IdentifiedClamp> clamp;           //!< identified's, with its error bound
  std::optional<tp::PassivityObserver> observer;       //!< replaces the sweep's choice when given
  std::optional<double> tolerance;                     //!< N on the clamps, replaces the sweep's
  std::optional<double> robot_tolerance;               //!< N on the clamps, robot_cost_tolerance
  std::optional<bool> return_needs_motion;             //!< replaces the sweep's choice when given
  std::optional<double> reserve;                       //!< J, replaces the sweep's energy reserve
  std::optional<double> recovery;                      //!< 1/s, replaces the sweep's gain recovery
  std::optional<bool> recover_absorbing;               //!< replaces recover_while_absorbing
  std::optional<bool> stiction_memory;                 //!< replaces the estimator's stiction memory
  std::optional<bool> stiction_through_zero;           //!< that memory holding through zero
  //! N on the clamps: the through-zero hold's contact level and, for identified, the robot-side
  //! tolerance (replaces the clamp model's measured free-motion error bound; robot_tolerance
  //! replaces it for the latter). Required with stiction_through_zero on other sources.
  std::optional<double> contact_level;
  //! The scenario with this source and the overrides.
  [[nodiscard]] sim::ClosedLoopConfig scenario(int ms, double loss, sim::ContactKind contact,
                                               tp::PassivityMode mode) const {
    auto c = sim::press_scenario(ms, loss, contact, mode, source, clamp);
    if (observer) c.passivity.observer = *observer;
    if (return_needs_motion) c.passivity.robot_return_needs_motion = *return_needs_motion;
    if (reserve) c.passivity.energy_reserve = *reserve;
    if (recovery) c.passivity.gain_recovery_rate = *recovery;
    if (recover_absorbing) c.passivity.recover_while_absorbing = *recover_absorbing;
    if (stiction_memory) c.stiction_memory = *stiction_memory;
    if (stiction_through_zero) c.stiction_through_zero = *stiction_through_zero;
    if (contact_level) {
      for (const int j : {2, 3}) {
        c.stiction_contact_level[j] = *contact_level;
        if (source == sim::ForceSource::identified) {
          c.passivity.robot_cost_tolerance[j] = *contact_level;
        }
      }
    }
    if (robot_tolerance) {
      for (const int j : {2, 3}) c.passivity.robot_cost_tolerance[j] = *robot_tolerance;
    }
    if (tolerance) {
      for (const int j : {2, 3}) c.passivity.estimate_tolerance[j] = *tolerance;
    }
    return c;
  }
};

//! The sweep (round trip x loss x contact), without passivity and with TDPA, markdown, with the
//! force from `src`; ends with one line per mode: "stable: K of N cases (force source S,
//! passivity off|tdpa)".
inline void table(const Source& src) {
  fmt::print(
      "| round trip | loss | contact | without: peak N | osc. after 1 s N | min energy J | "
      "max force N | verdict | TDPA: peak N | osc. after 1 s N | min energy J | max force N | "
      "hold N | felt/true | drift mrad | criteria |\n");
  fmt::print("|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|\n");
  int cases = 0, stable_off = 0, stable_tdpa = 0;
  for (const int ms : sim::press_round_trips_ms) {
    for (const double loss : {0.0, 0.1}) {
      for (const auto contact : {sim::ContactKind::soft_tissue, sim::ContactKind::stiff_stop}) {
        const auto a = sim::run_press(src.scenario(ms, loss, contact, tp::PassivityMode::observe),
                                      sim::press_seconds_without);
        const auto b = sim::run_press(src.scenario(ms, loss, contact, tp::PassivityMode::tdpa),
                                      sim::press_seconds_with);
        const std::string missed = sim::press_missed_criteria(b, ms);
        ++cases;
        stable_off += sim::press_stable_without(a) ? 1 : 0;
        stable_tdpa += missed.empty() ? 1 : 0;
        fmt::print(
            "| {} ms | {:.0f} % | {} | {:.2f} | {:.3f} | {:.3f} | {:.2f} | {} | {:.2f} | {:.3f} | "
            "{:.4f} | {:.2f} | {:.2f} | {:.2f} | {:.2f} | {} |\n",
            ms, loss * 100, to_string(contact), a.first_peak, a.decay_amplitude, a.min_energy,
            a.max_force, sim::press_verdict_without(a), b.first_peak, b.decay_amplitude,
            b.min_energy, b.max_force, b.hold_force, b.felt_ratio(), 1e3 * b.drift,
            missed.empty() ? std::string("met") : "NOT MET (" + missed + ")");
        std::fflush(stdout);
      }
    }
  }
  fmt::print("stable: {} of {} cases (force source {}, passivity off)\n", stable_off, cases,
             to_string(src.source));
  fmt::print("stable: {} of {} cases (force source {}, passivity tdpa)\n", stable_tdpa, cases,
             to_string(src.source));
}

//! Felt vs true stiffness up to a 1 s round trip, without passivity and with TDPA, markdown.
inline void transparency(sim::ContactKind contact, const Source& src) {
  // Felt stiffness: mean stylus force over the last second / the operator's penetration (stylus
  // radius past the touch); true: the same force ratio for the robot's penetration, so the two
  // agree when the stylus feels the contact the robot meets. Reference: the 0 ms run.
  fmt::print(
      "| round trip | mode | hold force N | felt N/m | true N/m | felt / true | felt / felt at 0 "
      "ms | TDPA force scale at the end | oscillation, last s, N |\n"
      "|---|---|---|---|---|---|---|---|---|\n");
  double reference[2] = {0.0, 0.0};
  for (const int ms : sim::transparency_round_trips_ms) {
    for (const auto mode : {tp::PassivityMode::observe, tp::PassivityMode::tdpa}) {
      std::vector<sim::ClosedLoopSample> samples;
      const auto r =
          sim::run_press(src.scenario(ms, 0.0, contact, mode), sim::press_seconds_with, &samples);
      const int m = mode == tp::PassivityMode::tdpa ? 1 : 0;
      if (ms == 0) reference[m] = r.felt_stiffness;
      fmt::print("| {} ms | {} | {:.2f} | {:.0f} | {:.0f} | {:.2f} | {:.2f} | {} | {:.3f} |\n", ms,
                 m == 1 ? "TDPA" : "off", r.hold_force, r.felt_stiffness, r.true_stiffness,
                 r.true_stiffness > 0.0 ? r.felt_stiffness / r.true_stiffness : 0.0,
                 reference[m] > 0.0 ? r.felt_stiffness / reference[m] : 0.0,
                 m == 1 ? fmt::format("{:.2f}", samples.back().passivity.force_gain) : "-",
                 r.late_amplitude);
      std::fflush(stdout);
    }
  }
}

//! One run's samples as CSV to `path`, and its figures.
inline void trace(const std::string& path, const sim::ClosedLoopConfig& config, double seconds) {
  std::vector<sim::ClosedLoopSample> samples;
  const auto r = sim::run_press(config, seconds, &samples);
  double min_to_robot = 0.0, min_to_operator = 0.0;
  for (const auto& s : samples) {
    min_to_robot = std::min(min_to_robot, s.passivity.energy_to_robot);
    min_to_operator = std::min(min_to_operator, s.passivity.energy_to_operator);
  }
  std::FILE* out = std::fopen(path.c_str(), "w");
  if (out == nullptr) throw std::runtime_error("cannot write " + path);
  fmt::print(out,
             "time,stylus_force,commanded_force,contact_force,desired,setpoint,robot,energy,"
             "damping,force_gain,drift,estimated_force,true_stylus_force,energy_to_robot,"
             "energy_to_operator,motor,current\n");
  for (const auto& s : samples) {
    fmt::print(
        out,
        "{:.4f},{:.5g},{:.5g},{:.5g},{:.6g},{:.6g},{:.6g},{:.6g},{:.5g},{:.4g},{:.5g},{:.5g},"
        "{:.5g},{:.6g},{:.6g},{:.6g},{:.5g}\n",
        s.time, s.stylus_force, s.commanded_force, s.contact_force, s.desired, s.setpoint, s.robot,
        s.passivity.energy, s.passivity.damping, s.passivity.force_gain, s.passivity.drift,
        s.estimated_force, s.true_stylus_force, s.passivity.energy_to_robot,
        s.passivity.energy_to_operator, s.motor, s.current);
  }
  if (std::fclose(out) != 0) throw std::runtime_error("cannot write " + path);
  fmt::print(
      "{}: {} samples; first peak {:.2f} N, oscillation 1 s later {:.3f} N, min energy "
      "{:.4f} J, max force {:.2f} N, hold {:.2f} N (true {:.2f} N, felt/true {:.2f}), drift "
      "{:.2f} mrad; lowest energy operator -> robot {:.4f} J, robot -> operator {:.4f} J\n",
      path, samples.size(), r.first_peak, r.decay_amplitude, r.min_energy, r.max_force,
      r.hold_force, r.true_hold_force, r.felt_ratio(), 1e3 * r.drift, min_to_robot,
      min_to_operator);
}

}  // namespace sweep_print
