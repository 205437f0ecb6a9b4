// The closed loop with the operator in it (sim::ClosedLoop, docs/passivity.md): the arm of table
// 5.1 presses clamp 1 into a contact through the TeleopLoop over a delayed, lossy network and
// holds, in virtual time. --table: the sweep without passivity and with TDPA (the scenarios and
// criteria of sim/passivity_sweep.hpp, as tests/sim/passivity_sweep_test.cpp runs them). --trace
// FILE: one run's samples as CSV (for the plots). --transparency: felt vs true stiffness up to a
// 1 s round trip. --force-source sensor|identified|preset-2016: what the loop feeds back (the
// ideal sensor, the clamp model identified on training runs (identify_training.hpp) or
// read with --model FILE, the 2016 preset). This program parses (options.cpp, sweep_options.hpp)
// and prints (sweep_print.hpp).
#include <fmt/format.h>

#include <cstdio>
#include <endohaptics/sim/passivity_sweep.hpp>
#include <endohaptics/workflow/command_line.hpp>
#include <exception>

#include "sweep_options.hpp"
#include "sweep_print.hpp"

namespace sim = endohaptics::sim;
namespace tp = endohaptics::teleop;

int main(int argc, char** argv) {
  sweep_options::Options o;
  const examples::Parsed parsed = sweep_options::parse_options(argc, argv, o);
  if (parsed.exit_code) return *parsed.exit_code;
  const auto contact =
      o.contact_name == "soft" ? sim::ContactKind::soft_tissue : sim::ContactKind::stiff_stop;
  // "off" runs the observer only: the loop renders exactly what it renders with the layer off
  // (tests/sim: "observe renders exactly what off renders") and the energy is visible.
  const auto mode = o.mode_name == "tdpa" ? tp::PassivityMode::tdpa : tp::PassivityMode::observe;
  try {
    const sweep_print::Source src = sweep_options::source(o);
    if (o.do_table) sweep_print::table(src);
    if (o.do_transparency) sweep_print::transparency(contact, src);
    if (!o.trace_path.empty()) {
      sweep_print::trace(o.trace_path, src.scenario(o.round_trip_ms, o.loss, contact, mode),
                         o.seconds);
    }
    if (!o.do_table && !o.do_transparency && o.trace_path.empty()) {
      fmt::print("{}", parsed.help);
      return 2;
    }
    endohaptics::workflow::require_written(stdout, "standard output");  // no false success
  } catch (const std::exception& e) {
    fmt::print(stderr, "endohaptics-passivity-sweep: {}\n", e.what());
    return 1;
  }
  return 0;
}
