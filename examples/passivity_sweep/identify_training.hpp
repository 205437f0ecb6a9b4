// The clamp model of the sweep's `identified` force source, identified the way the demo does
// (examples/demo.sh): the training runs of sim/passivity_sweep.hpp (force feedback off, other
// presses than the sweep's), then endohaptics-identify's workflow (workflow::run_identify) on
// their logs: a Hammerstein-Wiener model, inputs the reported current (through a play of the
// clamp's static friction) and velocity of clamp 1, output its true force; loaded as the bridge
// loads a clamp model file (files::bridge_joint_model). The sweep's own cases are never seen.
// Allocates, writes files, throws endohaptics::Error.
#pragma once

#include <algorithm>
#include <cmath>
#include <endohaptics/files/clamp_model_file.hpp>
#include <endohaptics/files/model_file.hpp>
#include <endohaptics/sim/passivity_sweep.hpp>
#include <endohaptics/workflow/identify_request.hpp>
#include <filesystem>
#include <memory>
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

//! N: the free-motion error bound of `model` on the training presses: the largest |estimate|
//! where the true force is 0, after the first 0.5 s of each press (the model fresh per press,
//! fed clamp 1's reported current, velocity, position and setpoint as the loop's rig reports
//! them). The stiction hold's contact level and the robot-side tolerance of the sweep.
[[nodiscard]] inline double free_motion_error(
    const endohaptics::estimation::BridgeJointModel& model) {
  double worst = 0.0;
  for (const auto& press : sim::training_presses()) {
    sim::ClosedLoopConfig c;
    c.contact = press.contact;
    c.contact_position = press.contact_position;
    c.press_depth = press.press_depth;
    c.approach_start = press.approach_start;
    c.approach_time = press.approach_time;
    c.force_gain = 0.0;
    auto loop = std::make_unique<sim::ClosedLoop>(c);
    auto m = model;
    const auto n = static_cast<int>(press.seconds * 1000.0 + 0.5);
    constexpr int j = sim::ClosedLoop::clamp1;
    for (int i = 0; i < n; ++i) {
      const auto s = loop->step();
      const auto state = loop->rig().state();
      endohaptics::estimation::JointSignals<double> sig;
      sig.current = state.current[j];
      sig.velocity = state.velocity[j];
      sig.position = state.position[j];
      sig.setpoint = state.position[j];
      const double f = m.force(sig);
      (void)m.advance(sig);
      if (s.time > 0.5 && loop->rig().truth().external_force[j] == 0.0) {
        worst = std::max(worst, std::fabs(f));
      }
    }
  }
  return worst;
}

}  // namespace sweep_identify
