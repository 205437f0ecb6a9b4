// The closed loop with the operator in it (sim::ClosedLoop, docs/passivity.md): the arm of table
// 5.1 presses clamp 1 into a contact through the TeleopLoop over a delayed, lossy network and
// holds, in virtual time. --table: the sweep of issue 17 without passivity and with TDPA (the
// same scenarios and criteria as tests/sim/passivity_sweep_test.cpp). --trace FILE: one run's
// samples as CSV (for the plots). --transparency: felt vs true stiffness up to a 1 s round trip.
#include <fmt/format.h>
#include <CLI/CLI.hpp>
#include <cstdio>
#include <endohaptics/sim/closed_loop.hpp>
#include <endohaptics/workflow/command_line.hpp>
#include <memory>
#include <string>
#include <vector>

#include "../cli_numbers.hpp"

namespace sim = endohaptics::sim;
namespace tp = endohaptics::teleop;

namespace {

sim::ClosedLoopConfig scenario(int round_trip_ms, double loss, sim::ContactKind contact,
                               tp::PassivityMode mode) {
  sim::ClosedLoopConfig c;
  c.round_trip = std::chrono::milliseconds(round_trip_ms);
  c.loss = loss;
  c.seed = 7;  // as the test
  c.contact = contact;
  c.passivity.mode = mode;
  return c;
}

sim::PressReport run(const sim::ClosedLoopConfig& config, double seconds,
                     std::vector<sim::ClosedLoopSample>* keep = nullptr) {
  auto loop = std::make_unique<sim::ClosedLoop>(config);
  std::vector<sim::ClosedLoopSample> samples;
  loop->run(seconds, samples);
  const sim::PressReport report = sim::analyze_press(*loop, samples);
  if (keep != nullptr) *keep = std::move(samples);
  return report;
}

// The test's criteria (tests/sim/passivity_sweep_test.cpp).
constexpr double epsilon = 0.015;    // J
constexpr double max_drift = 0.005;  // rad

std::string verdict_without(const sim::PressReport& r) {
  std::string why;
  if (!r.decays()) why += "no decay";
  if (r.min_energy < -epsilon) why += std::string(why.empty() ? "" : ", ") + "energy generated";
  if (r.max_force >= 3.0 - 1e-9) why += std::string(why.empty() ? "" : ", ") + "force limit";
  return why.empty() ? "stable" : "UNSTABLE (" + why + ")";
}

bool passes_with(const sim::PressReport& r) {
  return r.contact && r.min_energy > -epsilon && r.decays() && r.drift < max_drift &&
         r.max_force < 3.0 && r.hold_force > 0.4;
}

void table() {
  fmt::print(
      "| round trip | loss | contact | without: peak N | osc. after 1 s N | min energy J | "
      "max force N | verdict | TDPA: peak N | osc. after 1 s N | min energy J | max force N | "
      "hold N | drift mrad | criteria |\n");
  fmt::print("|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|\n");
  for (const int ms : {0, 20, 50, 100, 200}) {
    for (const double loss : {0.0, 0.1}) {
      for (const auto contact : {sim::ContactKind::soft_tissue, sim::ContactKind::stiff_stop}) {
        const auto a = run(scenario(ms, loss, contact, tp::PassivityMode::observe), 4.0);
        const auto b = run(scenario(ms, loss, contact, tp::PassivityMode::tdpa), 11.5);
        fmt::print(
            "| {} ms | {:.0f} % | {} | {:.2f} | {:.3f} | {:.3f} | {:.2f} | {} | {:.2f} | {:.3f} | "
            "{:.4f} | {:.2f} | {:.2f} | {:.2f} | {} |\n",
            ms, loss * 100, to_string(contact), a.first_peak, a.decay_amplitude, a.min_energy,
            a.max_force, verdict_without(a), b.first_peak, b.decay_amplitude, b.min_energy,
            b.max_force, b.hold_force, 1e3 * b.drift, passes_with(b) ? "met" : "NOT MET");
        std::fflush(stdout);
      }
    }
  }
}

void transparency(sim::ContactKind contact) {
  // Felt stiffness: mean stylus force over the last second / the operator's penetration (stylus
  // radius past the touch); true: the same force ratio for the robot's penetration, so the two
  // agree when the stylus feels the contact the robot meets. Reference: the 0 ms run.
  fmt::print(
      "| round trip | mode | hold force N | felt N/m | true N/m | felt / true | felt / felt at 0 "
      "ms | TDPA force scale at the end | oscillation, last s, N |\n"
      "|---|---|---|---|---|---|---|---|---|\n");
  double reference[2] = {0.0, 0.0};
  for (const int ms : {0, 50, 100, 200, 300, 500, 700, 1000}) {
    for (const auto mode : {tp::PassivityMode::observe, tp::PassivityMode::tdpa}) {
      std::vector<sim::ClosedLoopSample> samples;
      const auto r = run(scenario(ms, 0.0, contact, mode), 11.5, &samples);
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

void trace(const std::string& path, int ms, double loss, sim::ContactKind contact,
           tp::PassivityMode mode, double seconds) {
  std::vector<sim::ClosedLoopSample> samples;
  const auto r = run(scenario(ms, loss, contact, mode), seconds, &samples);
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

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{"endohaptics: press-and-hold with a simulated operator, with and without TDPA"};
  bool do_table = false, do_transparency = false;
  std::string trace_path, contact_name = "stiff", mode_name = "tdpa";
  int round_trip_ms = 100;
  double loss = 0.0, seconds = 11.5;
  app.add_flag("--table", do_table, "the sweep (round trip x loss x contact), markdown");
  app.add_flag("--transparency", do_transparency, "felt vs true stiffness, round trip to 1 s");
  app.add_option("--trace", trace_path, "write one run's samples as CSV to this file");
  app.add_option("--round-trip", round_trip_ms, "ms, for --trace")
      ->check(examples::number_in(0, tp::PassivityConfig::max_round_trip_ticks));
  app.add_option("--loss", loss, "probability, each direction, for --trace")
      ->check(examples::number_in(0.0, 1.0));
  app.add_option("--contact", contact_name, "soft or stiff")
      ->check(CLI::IsMember({"soft", "stiff"}));
  app.add_option("--mode", mode_name, "off or tdpa, for --trace")
      ->check(CLI::IsMember({"off", "tdpa"}));
  app.add_option("--seconds", seconds, "s simulated, for --trace")
      ->check(examples::number_in(0.1, 600.0));
  CLI11_PARSE(app, argc, argv);
  const auto contact =
      contact_name == "soft" ? sim::ContactKind::soft_tissue : sim::ContactKind::stiff_stop;
  // "off" runs the observer only: the loop renders exactly what it renders with the layer off
  // (tests/sim: "observe renders exactly what off renders") and the energy is visible.
  const auto mode = mode_name == "tdpa" ? tp::PassivityMode::tdpa : tp::PassivityMode::observe;
  try {
    if (do_table) table();
    if (do_transparency) transparency(contact);
    if (!trace_path.empty()) trace(trace_path, round_trip_ms, loss, contact, mode, seconds);
    if (!do_table && !do_transparency && trace_path.empty()) {
      fmt::print("{}", app.help());
      return 2;
    }
    endohaptics::workflow::require_written(stdout, "standard output");  // no false success
  } catch (const std::exception& e) {
    fmt::print(stderr, "endohaptics-passivity-sweep: {}\n", e.what());
    return 1;
  }
  return 0;
}
