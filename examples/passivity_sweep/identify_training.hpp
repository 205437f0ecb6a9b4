// The clamp model of the sweep's `identified` force source, identified the way the demo does
// (examples/demo.sh): the training runs of sim/passivity_sweep.hpp (force feedback off, other
// presses than the sweep's), then endohaptics-identify's workflow (workflow::run_identify) on
// their logs: a Hammerstein-Wiener model of order 2, inputs the reported current and velocity
// of clamp 1, output its true force; loaded as the bridge loads a clamp model file
// (files::bridge_joint_model). The sweep's own cases are never seen. Allocates, writes files,
// throws endohaptics::Error.
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

//! The request identify runs on `logs`: the demo's (order 2, reported current and velocity of
//! clamp 1 -> true force, dead zone auto, method best, time constants up to 2 s).
[[nodiscard]] inline workflow::IdentifyRequest training_request(std::vector<std::string> logs) {
  workflow::IdentifyRequest r;
  r.logs = std::move(logs);
  r.format = "csv";
  r.inputs = {"reported_current2", "reported_velocity2"};
  r.outputs = {"force2"};
  r.order = "2";
  r.method = "best";
  r.deadzone = "auto";
  r.sample_time = 0.001;
  r.max_time_constant = 2.0;
  return r;
}

//! Writes the training logs into `dir` (created), identifies, writes the model file
//! `dir`/clamp_model.json and returns the model as the bridge runs it.
[[nodiscard]] inline endohaptics::estimation::BridgeJointModel identify_sweep_clamp_model(
    const std::filesystem::path& dir) {
  std::filesystem::create_directories(dir);
  std::vector<std::string> logs;
  const auto presses = sim::training_presses();
  for (std::size_t i = 0; i < presses.size(); ++i) {
    const auto path = dir / ("training" + std::to_string(i) + ".csv");
    sim::write_training_log(path, presses[i]);
    logs.push_back(path.string());
  }
  const workflow::IdentifyReport report = workflow::run_identify(training_request(logs));
  workflow::check_scores(report);
  const auto model_path = dir / "clamp_model.json";
  endohaptics::files::save_model(model_path, report.model);
  return endohaptics::files::bridge_joint_model(report.model, "identified clamp model");
}

}  // namespace sweep_identify
