// The bridge as the programs assemble it (workflow::BridgeAssembly from a BridgeConfig and the
// loop settings), run over the in-memory transport against the emulated sbRIO and rig (sim/),
// in simulated time.
#include "endohaptics/workflow/bridge_assembly.hpp"

#include <doctest/doctest.h>

#include <chrono>
#include <endohaptics/model/presets_2016.hpp>
#include <endohaptics/sim/sbrio_emulator.hpp>
#include <endohaptics/sim/scripted_operator.hpp>
#include <endohaptics/sim/simulated_rig.hpp>
#include <endohaptics/transport/in_memory_transport.hpp>
#include <filesystem>
#include <memory>
#include <string>

#include "emulated_wire.hpp"
#include "test_support.hpp"

namespace workflow_bridge_assembly_test {

using endohaptics::test::message_of;
using endohaptics::test::TempDir;
using endohaptics::test::write_text;

namespace {

namespace transport = endohaptics::transport;
namespace sim = endohaptics::sim;
namespace tp = endohaptics::teleop;
namespace est = endohaptics::estimation;
namespace files = endohaptics::files;
namespace wf = endohaptics::workflow;
using namespace std::chrono_literals;
using Clock = endohaptics::ManualClock;
using Rig = sim::SimulatedRig<4>;
using Emulator = sim::SbrioEmulator<transport::InMemoryTransport<>, Rig, Clock>;
using Hand = sim::ScriptedOperator<Clock>;

using EmulatedWire = test_support::EmulatedWire<Emulator, Clock>;  // 100 us answers

// The rig side and the bridge assembled from `config` and `settings`.
struct Setup {
  Setup(const files::BridgeConfig& config, const wf::BridgeLoopSettings& settings)
      : hand(clock, config.operator_script), bridge(wire, hand, clock, config, settings) {}

  transport::InMemoryLink<> link;
  Clock clock{1s};
  Rig rig{sim::endowrist_2016_rig<4>(sim::Environment::tissue)};
  Emulator emulator{link.b(), rig, clock};
  EmulatedWire wire{&link.a(), &emulator, &clock};
  Hand hand;
  wf::BridgeAssembly<EmulatedWire, Hand, Clock> bridge;
};

// Runs `ticks` ticks; the robot obeyed each tick whose result is ok.
struct Run {
  std::uint64_t ticks = 0, ok = 0;
  double max_truth = 0.0;  // N, the true contact force at clamp 1
  tp::TickResult last{};
};

Run run(Setup& s, std::uint64_t ticks) {
  Run r;
  s.bridge.loop().run([&] { return r.ticks >= ticks; },
                      [&](const tp::TickResult& t) {
                        ++r.ticks;
                        r.ok += t.ok();
                        r.last = t;
                        r.max_truth = std::max(r.max_truth, s.rig.truth().contact_force[2]);
                      });
  return r;
}

}  // namespace

TEST_CASE("bridge assembly: the default configuration teleoperates the emulated rig") {
  const auto s = std::make_unique<Setup>(files::BridgeConfig{}, wf::BridgeLoopSettings{});
  CHECK(s->bridge.loop().config().period == 1ms);  // --rate 1000
  CHECK(s->bridge.estimator().joint_model<est::Motor::clamp1>().index() ==
        0);  // the appendix C yaw model
  const Run r = run(*s, 7000);
  CHECK(r.ticks == 7000);
  CHECK(r.ok >= 6990);  // the robot obeys: all but the first exchange or so
  CHECK(r.last.link == tp::LinkState::up);
  CHECK(r.last.measured.active_mask == r.last.enable_mask);
  CHECK(s->bridge.loop().stats().decode_errors() == 0);
  CHECK(s->bridge.loop().watchdog().link_losses() == 0);
  CHECK(s->emulator.counters().answered == 7000);
  CHECK(s->emulator.counters().watchdog_trips == 0);
  CHECK(s->bridge.paced().counters().steps >= 6900);  // the estimator on its 1 kHz grid
  CHECK(r.max_truth > 0.5);                           // the scripted grasp touches the tissue
}

TEST_CASE("bridge assembly: a clamp model file, --rate and TDPA from the settings") {
  const TempDir dir("bridge_assembly");
  // The appendix C yaw model with a 0.3 A dead zone, as endohaptics-identify would save it.
  files::save_model(
      dir.path() / "clamp.json",
      files::make_model_file(endohaptics::model::yaw_force_2016_hw(0.3),
                             {{"current", "A"}, {"velocity", "rad/s"}}, {{"force", "N"}}));
  write_text(dir.path() / "bridge.json", R"({"estimator": {"clamp_model": "clamp.json"}})");
  const files::BridgeConfig config = files::load_bridge_config(dir.path() / "bridge.json");
  const wf::BridgeLoopSettings settings{
      .rate = "500", .tdpa = true, .passivity_round_trip_ms = 20.0, .max_answer_lag = 3};
  const auto s = std::make_unique<Setup>(config, settings);
  const tp::TeleopLoopConfig& loop = s->bridge.loop().config();
  CHECK(loop.period == 2ms);
  CHECK(loop.passivity.mode == tp::PassivityMode::tdpa);
  CHECK(loop.passivity.round_trip_ticks == 10);  // 20 ms of 2 ms ticks
  CHECK(loop.passivity.force_limit == s->bridge.mapper().unclipped_joint_force());
  // The activation timeout allows 4 periods of answer lag beyond the default.
  CHECK(loop.safety.activation_timeout == doctest::Approx(wf::bridge_answer_allowance(3, 2e-3)));
  const auto* clamp = s->bridge.estimator()
                          .joint_model<est::Motor::clamp1>()
                          .get<est::IdentifiedHammersteinWiener<double>>();
  REQUIRE(clamp != nullptr);
  CHECK(clamp->model().input_nonlinearity().channel(0).upper() == 0.3);
  const Run r = run(*s, 3000);
  CHECK(r.ok >= 2990);
  CHECK(r.last.link == tp::LinkState::up);
  CHECK(s->emulator.counters().watchdog_trips == 0);
}

TEST_CASE("bridge assembly: an instrument's model set, its clamps different") {
  const TempDir dir("bridge_assembly");
  std::filesystem::create_directories(dir.path() / "sets");
  // Clamp 1 the appendix C yaw model with a 0.3 A dead zone, clamp 2 the 2016 code as run.
  files::save_model(
      dir.path() / "sets" / "yaw03.json",
      files::make_model_file(endohaptics::model::yaw_force_2016_hw(0.3),
                             {{"current", "A"}, {"velocity", "rad/s"}}, {{"force", "N"}}));
  write_text(dir.path() / "sets" / "EW7.json",
             R"({"format": "endohaptics model set", "format_version": 1, "instrument": "EW7",
                 "models": {"clamp1": "yaw03.json", "clamp2": "preset:clamp2016-as-run",
                            "roll": "preset:roll2016"}})");
  // Pitch renders no force (scale 0): it may be left out and runs its 2016 preset.
  write_text(dir.path() / "bridge.json", R"({"mapping": {"force_scale": [1, 1, 0]},
      "estimator": {"model_sets": "sets", "instrument": "EW7"}})");
  const files::BridgeConfig config = files::load_bridge_config(dir.path() / "bridge.json");
  const auto s = std::make_unique<Setup>(config, wf::BridgeLoopSettings{});
  const auto* clamp1 = s->bridge.estimator()
                           .joint_model<est::Motor::clamp1>()
                           .get<est::IdentifiedHammersteinWiener<double>>();
  REQUIRE(clamp1 != nullptr);
  CHECK(clamp1->model().input_nonlinearity().channel(0).upper() == 0.3);
  CHECK(
      s->bridge.estimator().joint_model<est::Motor::clamp2>().get<est::Clamp2016AsRun<double>>() !=
      nullptr);
  const std::string& said = s->bridge.force_models_description();
  CHECK(said.starts_with("instrument EW7 (model set " +
                         (dir.path() / "sets" / "EW7.json").string() +
                         "): clamp1 hammerstein_wiener ("));
  CHECK(said.ends_with(
      "clamp2 preset:clamp2016-as-run, roll preset:roll2016, pitch preset:pitch2016 (none in the "
      "set, no force feedback)"));
  const Run r = run(*s, 3000);
  CHECK(r.ok >= 2990);
  CHECK(r.last.link == tp::LinkState::up);
  CHECK(s->emulator.counters().watchdog_trips == 0);
  CHECK(s->bridge.paced().counters().rejected == 0);
}

TEST_CASE("bridge assembly: a rate too slow for the watchdog is refused, naming --rate") {
  files::BridgeConfig config;
  const std::string slow = message_of(
      [&] { (void)wf::bridge_loop_config(config, {.rate = "10"}, est::MotorVector::Ones()); });
  CHECK(slow.starts_with("--rate 10: at this rate "));
  CHECK(slow.find("use --rate ") != std::string::npos);
  CHECK(message_of([&] {
          (void)wf::bridge_loop_config(config, {.rate = "fast"}, est::MotorVector::Ones());
        }).find("--rate") != std::string::npos);
  const tp::TeleopLoopConfig max =
      wf::bridge_loop_config(config, {.rate = "max"}, est::MotorVector::Ones());
  CHECK(max.period == 0ns);
  CHECK(max.passivity.mode == config.loop.passivity.mode);  // no TDPA unless asked for
}

TEST_CASE("bridge assembly: --passivity tdpa runs the configuration's passivity section") {
  files::BridgeConfig config = files::parse_bridge_config(
      R"({ "passivity": { "observer": "per_direction", "gain_recovery_rate": 0.05,
                          "robot_cost_tolerance": [0, 0, 0.014, 0.014] } })");
  const est::MotorVector unclipped = est::MotorVector::Constant(1.5);
  const tp::TeleopLoopConfig loop = wf::bridge_loop_config(
      config, {.rate = "1000", .tdpa = true, .passivity_round_trip_ms = 50.0}, unclipped);
  CHECK(loop.passivity.mode == tp::PassivityMode::tdpa);
  CHECK(loop.passivity.round_trip_ticks == 50);
  CHECK(loop.passivity.force_limit == unclipped);  // the program's, not the file's
  CHECK(loop.passivity.observer == tp::PassivityObserver::per_direction);
  CHECK(loop.passivity.gain_recovery_rate == 0.05);
  CHECK(loop.passivity.robot_cost_tolerance[3] == 0.014);
  loop.validate();
}

}  // namespace workflow_bridge_assembly_test
