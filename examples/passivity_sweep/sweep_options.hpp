// How endohaptics-passivity-sweep's options (options.hpp) make the force source
// (sweep_print::Source): the clamp model identified on the training presses (identify_training.hpp)
// or read from a file, with its free-motion error bound measured (sim::identified_clamp), and the
// layer's overrides.
#pragma once

#include <fmt/format.h>

#include <cstdio>
#include <endohaptics/files/clamp_model_file.hpp>
#include <endohaptics/sim/passivity_sweep.hpp>
#include <filesystem>
#include <stdexcept>
#include <string>

#include "identify_training.hpp"
#include "options.hpp"
#include "sweep_print.hpp"

namespace sweep_options {

namespace sim = endohaptics::sim;
namespace tp = endohaptics::teleop;

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
