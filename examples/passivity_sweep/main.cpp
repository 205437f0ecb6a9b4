// The closed loop with the operator in it (sim::ClosedLoop, docs/passivity.md): the arm of table
// 5.1 presses clamp 1 into a contact through the TeleopLoop over a delayed, lossy network and
// holds, in virtual time. --table: the sweep without passivity and with TDPA (the scenarios and
// criteria of sim/passivity_sweep.hpp, as tests/sim/passivity_sweep_test.cpp runs them). --trace
// FILE: one run's samples as CSV (for the plots). --transparency: felt vs true stiffness up to a
// 1 s round trip. --force-source sensor|identified|preset-2016: what the loop feeds back (the
// ideal sensor, the clamp model identified on training runs (sim/sweep_identification.hpp) or
// read with --model FILE, the 2016 preset). This program parses and prints (sweep_print.hpp).
#include <fmt/format.h>

#include <CLI/CLI.hpp>
#include <cstdio>
#include <endohaptics/files/clamp_model_file.hpp>
#include <endohaptics/sim/passivity_sweep.hpp>
#include <endohaptics/workflow/command_line.hpp>
#include <filesystem>
#include <string>
#include "identify_training.hpp"

#include "../cli_numbers.hpp"
#include "sweep_print.hpp"

namespace sim = endohaptics::sim;
namespace tp = endohaptics::teleop;

int main(int argc, char** argv) {
  CLI::App app{"endohaptics: press-and-hold with a simulated operator, with and without TDPA"};
  bool do_table = false, do_transparency = false;
  std::string trace_path, contact_name = "stiff", mode_name = "tdpa", source_name = "sensor";
  std::string model_path, training_dir;
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
  app.add_option("--force-source", source_name,
                 "sensor (ideal), identified (a clamp model from training runs, or --model), "
                 "preset-2016 (appendix C yaw model)")
      ->check(CLI::IsMember({"sensor", "identified", "preset-2016"}));
  app.add_option("--model", model_path,
                 "clamp model file for --force-source identified (default: identify one on "
                 "training runs)");
  app.add_option("--training-dir", training_dir,
                 "where the training logs and the identified clamp_model.json go (default: a "
                 "directory under the system's temporary one)");
  std::string observer_name;
  double tolerance = -1.0;
  app.add_option("--observer", observer_name,
                 "combined or per-direction (default: the sweep's choice for the force source)")
      ->check(CLI::IsMember({"combined", "per-direction"}));
  app.add_option("--estimate-tolerance", tolerance,
                 "N on the clamps: the estimate error the observer tolerates (default: the "
                 "sweep's choice for the force source)")
      ->check(examples::number_in(0.0, 10.0));
  double robot_tolerance = -1.0;
  app.add_option("--robot-tolerance", robot_tolerance,
                 "N on the clamps: the force below which the robot-side controller does not "
                 "hold a setpoint step back (default: the sweep's choice for the force source: the "
                 "identified model's free-motion error bound, --contact-level)")
      ->check(examples::number_in(0.0, 10.0));
  std::string robot_return;
  app.add_option("--robot-return", robot_return,
                 "setpoint-and-robot or setpoint: what shows energy coming back at the robot port "
                 "(default: the sweep's choice for the force source)")
      ->check(CLI::IsMember({"setpoint-and-robot", "setpoint"}));
  double reserve = 0.0;
  app.add_option("--energy-reserve", reserve,
                 "J per joint the operator-side controller lets the observer borrow (default: the "
                 "sweep's choice for the force source)")
      ->check(examples::number_in(1e-6, 1.0));
  double recovery = 0.0;
  app.add_option("--gain-recovery", recovery,
                 "1/s the operator-side force scale comes back at (default: the sweep's choice)")
      ->check(examples::number_in(1e-6, 100.0));
  std::string recover;
  app.add_option("--recover", recover,
                 "always-scaled or while-absorbing: when the operator-side force scale follows "
                 "the deficit (default: the sweep's choice)")
      ->check(CLI::IsMember({"always-scaled", "while-absorbing"}));
  std::string fit_name = "play";
  app.add_option("--identify-fit", fit_name,
                 "play or deadzone: the clamp model identified with the current through a play of "
                 "the clamp's static friction (the demo's way, default) or with a current dead "
                 "zone (order 2, as before the play)")
      ->check(CLI::IsMember({"play", "deadzone"}));
  double contact_level = -1.0;
  app.add_option(
         "--contact-level", contact_level,
         "N on the clamps: the through-zero stiction hold's contact level and the default "
         "--robot-tolerance (default: the identified model's free-motion error bound on its "
         "training presses, measured; required with --stiction-memory through-zero on the other "
         "sources)")
      ->check(examples::number_in(0.0, 10.0));
  std::string stiction;
  app.add_option(
         "--stiction-memory", stiction,
         "on, through-zero or off: the estimator's stiction memory with the simulated "
         "instrument's constants (through-zero: holding while the estimate changes sign, "
         "estimation::StictionHold; default: off: the identified model's current play holds "
         "the static-friction band itself)")
      ->check(CLI::IsMember({"on", "through-zero", "off"}));
  CLI11_PARSE(app, argc, argv);
  const auto contact =
      contact_name == "soft" ? sim::ContactKind::soft_tissue : sim::ContactKind::stiff_stop;
  // "off" runs the observer only: the loop renders exactly what it renders with the layer off
  // (tests/sim: "observe renders exactly what off renders") and the energy is visible.
  const auto mode = mode_name == "tdpa" ? tp::PassivityMode::tdpa : tp::PassivityMode::observe;
  try {
    sweep_print::Source src;
    if (source_name == "identified") {
      src.source = sim::ForceSource::identified;
      if (!model_path.empty()) {
        src.clamp = sim::identified_clamp(endohaptics::files::load_bridge_joint_model(model_path));
      } else {
        const std::filesystem::path dir =
            training_dir.empty()
                ? std::filesystem::temp_directory_path() / "endohaptics-passivity-training"
                : std::filesystem::path(training_dir);
        const auto fit = fit_name == "play" ? sweep_identify::TrainingFit::play
                                            : sweep_identify::TrainingFit::deadzone;
        src.clamp = sim::identified_clamp(sweep_identify::identify_sweep_clamp_model(dir, fit));
        fmt::print(stderr,
                   "endohaptics-passivity-sweep: clamp model identified ({}) on {} training "
                   "runs: {}\n",
                   fit_name, sim::training_presses().size(), (dir / "clamp_model.json").string());
      }
      fmt::print(stderr,
                 "endohaptics-passivity-sweep: its free-motion error on the training presses: "
                 "{:.3f} N\n",
                 src.clamp->free_motion_error);
    } else if (source_name == "preset-2016") {
      src.source = sim::ForceSource::preset_2016;
    } else if (!model_path.empty()) {
      throw std::runtime_error("--model needs --force-source identified");
    }
    if (!observer_name.empty()) {
      src.observer = observer_name == "combined" ? tp::PassivityObserver::combined
                                                 : tp::PassivityObserver::per_direction;
    }
    if (contact_level >= 0.0) src.contact_level = contact_level;
    if (tolerance >= 0.0) src.tolerance = tolerance;
    if (robot_tolerance >= 0.0) src.robot_tolerance = robot_tolerance;
    if (reserve > 0.0) src.reserve = reserve;
    if (recovery > 0.0) src.recovery = recovery;
    if (!recover.empty()) src.recover_absorbing = recover == "while-absorbing";
    if (!stiction.empty()) {
      src.stiction_memory = stiction != "off";
      src.stiction_through_zero = stiction == "through-zero";
      if (*src.stiction_through_zero && source_name != "identified" && !src.contact_level) {
        throw std::runtime_error(
            "--stiction-memory through-zero needs --contact-level with --force-source " +
            source_name + " (the identified source's is its model's measured free-motion error)");
      }
    }
    if (!robot_return.empty()) src.return_needs_motion = robot_return == "setpoint-and-robot";
    if (do_table) sweep_print::table(src);
    if (do_transparency) sweep_print::transparency(contact, src);
    if (!trace_path.empty()) {
      sweep_print::trace(trace_path, src.scenario(round_trip_ms, loss, contact, mode), seconds);
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
