// The closed loop with the operator in it (sim::ClosedLoop, docs/passivity.md): the arm of table
// 5.1 presses clamp 1 into a contact through the TeleopLoop over a delayed, lossy network and
// holds, in virtual time. --table: the sweep without passivity and with TDPA (the scenarios and
// criteria of sim/passivity_sweep.hpp, as tests/sim/passivity_sweep_test.cpp runs them). --trace
// FILE: one run's samples as CSV (for the plots). --transparency: felt vs true stiffness up to a
// 1 s round trip. This program parses and prints (sweep_print.hpp).
#include <fmt/format.h>

#include <CLI/CLI.hpp>
#include <cstdio>
#include <endohaptics/sim/passivity_sweep.hpp>
#include <endohaptics/workflow/command_line.hpp>
#include <string>

#include "../cli_numbers.hpp"
#include "sweep_print.hpp"

namespace sim = endohaptics::sim;
namespace tp = endohaptics::teleop;

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
    if (do_table) sweep_print::table();
    if (do_transparency) sweep_print::transparency(contact);
    if (!trace_path.empty()) {
      sweep_print::trace(trace_path, sim::press_scenario(round_trip_ms, loss, contact, mode),
                         seconds);
    }
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
