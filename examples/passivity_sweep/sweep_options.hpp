// endohaptics-passivity-sweep's options and how they make the force source (sweep_print::Source):
// the clamp model identified on the training presses (identify_training.hpp) or read from a file,
// with its free-motion error bound measured (sim::identified_clamp), and the layer's overrides.
#pragma once

#include <fmt/format.h>

#include <CLI/CLI.hpp>
#include <cstdio>
#include <endohaptics/files/clamp_model_file.hpp>
#include <endohaptics/sim/passivity_sweep.hpp>
#include <filesystem>
#include <stdexcept>
#include <string>

#include "../cli_numbers.hpp"
#include "identify_training.hpp"
#include "sweep_print.hpp"

namespace sweep_options {

namespace sim = endohaptics::sim;
namespace tp = endohaptics::teleop;

//! What the command line asks for.
struct Options {
  bool do_table = false, do_transparency = false;
  std::string trace_path, contact_name = "stiff", mode_name = "tdpa", source_name = "sensor";
  std::string model_path, training_dir;
  int round_trip_ms = 100;
  double loss = 0.0, seconds = 11.5;
  std::string observer_name;
  double tolerance = -1.0;
  double robot_tolerance = -1.0;
  std::string robot_return;
  double reserve = 0.0;
  double recovery = 0.0;
  std::string recover;
  std::string fit_name = "play";
  double contact_level = -1.0;
  std::string stiction;
};

//! Declares the options on `app`, writing into `o`.
inline void add(CLI::App& app, Options& o) {
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

//! The force source the options ask for: identifies the clamp model (or reads --model) for
//! identified and says so on standard error. Throws on options that cannot apply together.
[[nodiscard]] inline sweep_print::Source source(const Options& o) {
  sweep_print::Source src;
  if (o.source_name == "identified") {
    src.source = sim::ForceSource::identified;
    if (!o.model_path.empty()) {
      src.clamp = sim::identified_clamp(endohaptics::files::load_bridge_joint_model(o.model_path));
    } else {
      const std::filesystem::path dir =
          o.training_dir.empty()
              ? std::filesystem::temp_directory_path() / "endohaptics-passivity-training"
              : std::filesystem::path(o.training_dir);
      const auto fit = o.fit_name == "play" ? sweep_identify::TrainingFit::play
                                            : sweep_identify::TrainingFit::deadzone;
      src.clamp = sim::identified_clamp(sweep_identify::identify_sweep_clamp_model(dir, fit));
      fmt::print(stderr,
                 "endohaptics-passivity-sweep: clamp model identified ({}) on {} training "
                 "runs: {}\n",
                 o.fit_name, sim::training_presses().size(), (dir / "clamp_model.json").string());
    }
    fmt::print(stderr,
               "endohaptics-passivity-sweep: its free-motion error on the training presses: "
               "{:.3f} N\n",
               src.clamp->free_motion_error);
  } else if (o.source_name == "preset-2016") {
    src.source = sim::ForceSource::preset_2016;
  } else if (!o.model_path.empty()) {
    throw std::runtime_error("--model needs --force-source identified");
  }
  if (!o.observer_name.empty()) {
    src.observer = o.observer_name == "combined" ? tp::PassivityObserver::combined
                                                 : tp::PassivityObserver::per_direction;
  }
  if (o.contact_level >= 0.0) src.contact_level = o.contact_level;
  if (o.tolerance >= 0.0) src.tolerance = o.tolerance;
  if (o.robot_tolerance >= 0.0) src.robot_tolerance = o.robot_tolerance;
  if (o.reserve > 0.0) src.reserve = o.reserve;
  if (o.recovery > 0.0) src.recovery = o.recovery;
  if (!o.recover.empty()) src.recover_absorbing = o.recover == "while-absorbing";
  if (!o.stiction.empty()) {
    src.stiction_memory = o.stiction != "off";
    src.stiction_through_zero = o.stiction == "through-zero";
    if (*src.stiction_through_zero && o.source_name != "identified" && !src.contact_level) {
      throw std::runtime_error(
          "--stiction-memory through-zero needs --contact-level with --force-source " +
          o.source_name + " (the identified source's is its model's measured free-motion error)");
    }
  }
  if (!o.robot_return.empty()) src.return_needs_motion = o.robot_return == "setpoint-and-robot";
  return src;
}

}  // namespace sweep_options
