// endohaptics-passivity-sweep's options (examples/program_options.hpp).
#include "options.hpp"

#include <endohaptics/teleop/passivity.hpp>

#include "../cli_numbers.hpp"
#include "../parse_command_line.hpp"

namespace sweep_options {

namespace {

namespace tp = endohaptics::teleop;

//! Declares the options on `app`, writing into `o`.
void add(CLI::App& app, Options& o) {
  app.add_flag("--table", o.do_table, "the sweep (round trip x loss x contact), markdown");
  app.add_flag("--transparency", o.do_transparency, "felt vs true stiffness, round trip to 1 s");
  app.add_option("--trace", o.trace_path, "write one run's samples as CSV to this file");
  app.add_option("--round-trip", o.round_trip_ms, "ms, for --trace")
      ->check(examples::number_in(0, tp::PassivityConfig::max_round_trip_ticks));
  app.add_option("--loss", o.loss, "probability, each direction, for --trace")
      ->check(examples::number_in(0.0, 1.0));
  app.add_option("--contact", o.contact_name, "soft or stiff")
      ->check(CLI::IsMember({"soft", "stiff"}));
  app.add_option("--mode", o.mode_name, "off or tdpa, for --trace")
      ->check(CLI::IsMember({"off", "tdpa"}));
  app.add_option("--seconds", o.seconds, "s simulated, for --trace")
      ->check(examples::number_in(0.1, 600.0));
  app.add_option("--force-source", o.source_name,
                 "sensor (ideal), identified (a clamp model from training runs, or --model), "
                 "preset-2016 (appendix C yaw model)")
      ->check(CLI::IsMember({"sensor", "identified", "preset-2016"}));
  app.add_option("--model", o.model_path,
                 "clamp model file for --force-source identified (default: identify one on "
                 "training runs)");
  app.add_option("--training-dir", o.training_dir,
                 "where the training logs and the identified clamp_model.json go (default: a "
                 "directory under the system's temporary one)");
  app.add_option("--observer", o.observer_name,
                 "combined or per-direction (default: the sweep's choice for the force source)")
      ->check(CLI::IsMember({"combined", "per-direction"}));
  app.add_option("--estimate-tolerance", o.tolerance,
                 "N on the clamps: the estimate error the observer tolerates (default: the "
                 "sweep's choice for the force source)")
      ->check(examples::number_in(0.0, 10.0));
  app.add_option("--robot-tolerance", o.robot_tolerance,
                 "N on the clamps: the force below which the robot-side controller does not "
                 "hold a setpoint step back (default: the sweep's choice for the force source: the "
                 "identified model's free-motion error bound, --contact-level)")
      ->check(examples::number_in(0.0, 10.0));
  app.add_option("--robot-return", o.robot_return,
                 "setpoint-and-robot or setpoint: what shows energy coming back at the robot port "
                 "(default: the sweep's choice for the force source)")
      ->check(CLI::IsMember({"setpoint-and-robot", "setpoint"}));
  app.add_option("--energy-reserve", o.reserve,
                 "J per joint the operator-side controller lets the observer borrow (default: the "
                 "sweep's choice for the force source)")
      ->check(examples::number_in(1e-6, 1.0));
  app.add_option("--gain-recovery", o.recovery,
                 "1/s the operator-side force scale comes back at (default: the sweep's choice)")
      ->check(examples::number_in(1e-6, 100.0));
  app.add_option("--recover", o.recover,
                 "always-scaled or while-absorbing: when the operator-side force scale follows "
                 "the deficit (default: the sweep's choice)")
      ->check(CLI::IsMember({"always-scaled", "while-absorbing"}));
  app.add_option("--identify-fit", o.fit_name,
                 "play or deadzone: the clamp model identified with the current through a play of "
                 "the clamp's static friction (the demo's way, default) or with a current dead "
                 "zone (order 2, as before the play)")
      ->check(CLI::IsMember({"play", "deadzone"}));
  app.add_option(
         "--contact-level", o.contact_level,
         "N on the clamps: the through-zero stiction hold's contact level and the default "
         "--robot-tolerance (default: the identified model's free-motion error bound on its "
         "training presses, measured; required with --stiction-memory through-zero on the other "
         "sources)")
      ->check(examples::number_in(0.0, 10.0));
  app.add_option(
         "--stiction-memory", o.stiction,
         "on, through-zero or off: the estimator's stiction memory with the simulated "
         "instrument's constants (through-zero: holding while the estimate changes sign, "
         "estimation::StictionHold; default: off: the identified model's current play holds "
         "the static-friction band itself)")
      ->check(CLI::IsMember({"on", "through-zero", "off"}));
}

}  // namespace

examples::Parsed parse_options(int argc, const char* const* argv, Options& o) {
  CLI::App app{"endohaptics: press-and-hold with a simulated operator, with and without TDPA"};
  add(app, o);
  return examples::parse_command_line(app, argc, argv);
}

}  // namespace sweep_options
