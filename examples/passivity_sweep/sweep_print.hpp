// What endohaptics-passivity-sweep prints: the sweep's table, the transparency table and one
// run's trace (CSV), over the library's scenarios and criteria (sim/passivity_sweep.hpp).
#pragma once

#include <fmt/format.h>

#include <cstdio>
#include <endohaptics/sim/passivity_sweep.hpp>
#include <endohaptics/workflow/command_line.hpp>
#include <string>
#include <utility>
#include <vector>

namespace sweep_print {

namespace sim = endohaptics::sim;
namespace tp = endohaptics::teleop;

//! The sweep (round trip x loss x contact), without passivity and with TDPA, markdown.
inline void table() {
  fmt::print(
      "| round trip | loss | contact | without: peak N | osc. after 1 s N | min energy J | "
      "max force N | verdict | TDPA: peak N | osc. after 1 s N | min energy J | max force N | "
      "hold N | drift mrad | criteria |\n");
  fmt::print("|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|\n");
  for (const int ms : sim::press_round_trips_ms) {
    for (const double loss : {0.0, 0.1}) {
      for (const auto contact : {sim::ContactKind::soft_tissue, sim::ContactKind::stiff_stop}) {
        const auto a =
            sim::run_press(sim::press_scenario(ms, loss, contact, tp::PassivityMode::observe),
                           sim::press_seconds_without);
        const auto b =
            sim::run_press(sim::press_scenario(ms, loss, contact, tp::PassivityMode::tdpa),
                           sim::press_seconds_with);
        fmt::print(
            "| {} ms | {:.0f} % | {} | {:.2f} | {:.3f} | {:.3f} | {:.2f} | {} | {:.2f} | {:.3f} | "
            "{:.4f} | {:.2f} | {:.2f} | {:.2f} | {} |\n",
            ms, loss * 100, to_string(contact), a.first_peak, a.decay_amplitude, a.min_energy,
            a.max_force, sim::press_verdict_without(a), b.first_peak, b.decay_amplitude,
            b.min_energy, b.max_force, b.hold_force, 1e3 * b.drift,
            sim::press_meets_criteria(b) ? "met" : "NOT MET");
        std::fflush(stdout);
      }
    }
  }
}

//! Felt vs true stiffness up to a 1 s round trip, without passivity and with TDPA, markdown.
inline void transparency(sim::ContactKind contact) {
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
      const auto r = sim::run_press(sim::press_scenario(ms, 0.0, contact, mode),
                                    sim::press_seconds_with, &samples);
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
  std::FILE* out = std::fopen(path.c_str(), "w");
  if (out == nullptr) throw std::runtime_error("cannot write " + path);
  fmt::print(out,
             "time,stylus_force,commanded_force,contact_force,desired,setpoint,robot,energy,"
             "damping,force_gain,drift\n");
  for (const auto& s : samples) {
    fmt::print(
        out, "{:.4f},{:.5g},{:.5g},{:.5g},{:.6g},{:.6g},{:.6g},{:.6g},{:.5g},{:.4g},{:.5g}\n",
        s.time, s.stylus_force, s.commanded_force, s.contact_force, s.desired, s.setpoint, s.robot,
        s.passivity.energy, s.passivity.damping, s.passivity.force_gain, s.passivity.drift);
  }
  if (std::fclose(out) != 0) throw std::runtime_error("cannot write " + path);
  fmt::print(
      "{}: {} samples; first peak {:.2f} N, oscillation 1 s later {:.3f} N, min energy "
      "{:.4f} J, max force {:.2f} N, hold {:.2f} N, drift {:.2f} mrad\n",
      path, samples.size(), r.first_peak, r.decay_amplitude, r.min_energy, r.max_force,
      r.hold_force, 1e3 * r.drift);
}

}  // namespace sweep_print
