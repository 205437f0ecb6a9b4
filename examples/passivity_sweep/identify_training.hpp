// The clamp model of the sweep's `identified` force source, identified the way the demo does
// (examples/demo.sh): the training runs of sim/passivity_sweep.hpp (force feedback off, other
// presses than the sweep's), then endohaptics-identify's workflow (workflow::run_identify) on
// their logs: a Hammerstein-Wiener model, inputs the reported current (through a play of the
// clamp's static friction) and velocity of clamp 1, output its true force; loaded as the bridge
// loads a clamp model file (files::bridge_joint_model). The sweep's own cases are never seen.
// Allocates, writes files, throws endohaptics::Error.
#pragma once

#include <endohaptics/files/clamp_model_file.hpp>
#include <endohaptics/files/model_file.hpp>
#include <endohaptics/sim/passivity_sweep.hpp>
#include <endohaptics/workflow/identify_request.hpp>
#include <filesystem>
#include <string>
#include <utility>
#include <vector>

namespace sweep_identify {

namespace sim = endohaptics::sim;
namespace workflow = endohaptics::workflow;

//! How the clamp model is identified: `play` as the demo identifies pitch and the clamps now
//! (the current through a play of the clamp's K_s, sim::clamp_current_play, no current dead zone,
//! the order by the causal score up to 4); `deadzone` as it did before the play (order 2, dead
//! zone auto), for comparison.
enum class TrainingFit { play, deadzone };

//! The request identify runs on `logs`: the demo's (inputs the reported current and velocity of
//! clamp 1, output its true force, method best, time constants up to 2 s; the rest by `fit`).
[[nodiscard]] inline workflow::IdentifyRequest training_request(
    std::vector<std::string> logs, TrainingFit fit = TrainingFit::play) {
  workflow::IdentifyRequest r;
  r.logs = std::move(logs);
  r.format = "csv";
  r.inputs = {"reported_current2", "reported_velocity2"};
  r.outputs = {"force2"};
  r.method = "best";
  r.sample_time = 0.001;
  r.max_time_constant = 2.0;
  if (fit == TrainingFit::play) {
    r.order = "auto";
    r.max_order = 4;
    r.deadzone = "0,auto";
    r.current_play = sim::clamp_current_play();
  } else {
    r.order = "2";
    r.deadzone = "auto";
  }
  return r;
}

//! Writes the training logs into `dir` (created), identifies, writes the model file
//! `dir`/clamp_model.json and returns the model as the bridge runs it.
[[nodiscard]] inline endohaptics::estimation::BridgeJointModel identify_sweep_clamp_model(
    const std::filesystem::path& dir, TrainingFit fit = TrainingFit::play) {
  std::filesystem::create_directories(dir);
  std::vector<std::string> logs;
  const auto presses = sim::training_presses();
  for (std::size_t i = 0; i < presses.size(); ++i) {
    const auto path = dir / ("training" + std::to_string(i) + ".csv");
    sim::write_training_log(path, presses[i]);
    logs.push_back(path.string());
  }
  const workflow::IdentifyReport report = workflow::run_identify(training_request(logs, fit));
  workflow::check_scores(report);
  const auto model_path = dir / "clamp_model.json";
  endohaptics::files::save_model(model_path, report.model);
  return endohaptics::files::bridge_joint_model(report.model, "identified clamp model");
}

}  // namespace sweep_identify
