// Model-file kinds "stall_hold", "push_load_observer" and "bidirectional_load_observer" (issue
// 15): round trips, hostile input,
// and a file of each kind loaded by the bridge configuration and run in its ForceEstimator.
#include "alloc_counter.hpp"  // first: counts every heap allocation of this executable

#include <doctest/doctest.h>

#include <cmath>
#include <filesystem>
#include <limits>
#include <nlohmann/json.hpp>
#include <string>

#include "endohaptics/estimation/bidirectional_load_observer.hpp"
#include "endohaptics/estimation/current_offset_reference.hpp"
#include "endohaptics/estimation/push_load_observer.hpp"
#include "endohaptics/estimation/stall_hold.hpp"
#include "endohaptics/files/bridge_config.hpp"
#include "endohaptics/files/model_file.hpp"
#include "test_support.hpp"

namespace files_joint_model_file_test {

namespace files = endohaptics::files;
namespace est = endohaptics::estimation;
using endohaptics::test::message_of;
using endohaptics::test::TempDir;
using endohaptics::test::write_text;
using nlohmann::json;

namespace {

const std::vector<files::SignalInfo> clamp_inputs{{"current", "A"}, {"velocity", "rad/s"}};

files::ModelFile stall_hold_file() {
  est::StallHoldParameters<double> p;
  p.gain = -7.5;
  p.side = est::StallHoldSide::negative;
  p.current_deadzone = 0.18;
  p.sample_time = 0.01;
  return files::make_joint_model_file(p, clamp_inputs, {{"force", "N"}},
                                      {.method = "stall_hold", .files = {"a.csv", "b.csv"}});
}

files::ModelFile observer_file() {
  est::PushLoadObserverParameters<double> p;
  p.current_per_load = 1.45;
  p.current_offset = 0.07;
  p.initial_load = 0.04;
  p.output_offset = -0.002;
  p.output_slope = 0.1;
  p.process_variance = 1e-8;
  p.back_current_per_load = 0.8;
  p.back_current_offset = -0.1;
  p.back_current_per_velocity = -0.004;
  p.back_variance = 4e-4;
  return files::make_joint_model_file(p, clamp_inputs, {{"grip_torque", "N m"}});
}

files::ModelFile bidirectional_file() {
  est::BidirectionalLoadObserverParameters<double> p;
  p.forward_gain = -1.41e-3;
  p.forward_gain_stroke = -2.3e-4;
  p.forward_offset = 0.066;
  p.backward_gain = -6.1e-4;
  p.backward_offset = -0.09;
  p.backward_offset_stroke = 0.035;
  p.forward_variance = 9000.0;
  p.backward_variance = 30000.0;
  p.friction_variance = 62.0;
  p.load_process_variance = 0.002;
  p.initial_load = -65.8;
  p.initial_variance = 1180.0;
  p.output_offset = 0.26;
  p.output_shape << 0.2, 0.25, -0.38, 1.15, 1.1, 0.66, 0.12, -0.78;
  p.output_shape_per_load << 0.008, -0.012, 0.003, 0.0, -0.003, 0.0, 0.01, 0.089;
  return files::make_joint_model_file(p, clamp_inputs, {{"grip_torque", "mN m"}});
}

// The message model_from_json gives for `j` (source "m.json").
std::string error_of(const json& j) {
  return message_of([&] { (void)files::model_from_json(j, "m.json"); });
}

}  // namespace

TEST_CASE("joint-model files: both kinds round-trip through JSON and disk") {
  const files::ModelFile s = stall_hold_file();
  CHECK(s.kind() == files::ModelKind::stall_hold);
  CHECK(s.is_joint_model());
  const json j = files::to_json(s);
  CHECK(j["kind"] == "stall_hold");
  CHECK_FALSE(j.contains("A"));
  CHECK_FALSE(j.contains("states"));
  CHECK(j["parameters"]["side"] == "negative");
  CHECK(j["version"] == 2);
  const files::ModelFile back = files::model_from_json(j);
  CHECK(back.state_space.sample_time() == 0.01);
  CHECK(back.provenance.files == std::vector<std::string>{"a.csv", "b.csv"});
  const auto p = files::joint_model_parameters<est::StallHoldParameters<double>>(back);
  CHECK(p.current_deadzone == 0.18);
  CHECK(p.side == est::StallHoldSide::negative);
  CHECK(p.gain == -7.5);
  CHECK(p.sample_time == 0.01);

  TempDir dir("joint_model");
  files::save_model(dir.path() / "o.json", observer_file());
  const files::ModelFile o = files::load_model(dir.path() / "o.json");
  CHECK(o.kind() == files::ModelKind::push_load_observer);
  CHECK(files::to_json(o) == files::to_json(observer_file()));
  const auto q = files::joint_model_parameters<est::PushLoadObserverParameters<double>>(o);
  CHECK(q.current_per_load == 1.45);
  CHECK(q.initial_load == 0.04);
  CHECK(q.sample_time == 0.001);
  CHECK(q.back_current_per_load == 0.8);
  CHECK(q.back_current_offset == -0.1);
  CHECK(q.back_current_per_velocity == -0.004);
  CHECK(q.back_variance == 4e-4);
  CHECK_NOTHROW((void)est::PushLoadObserver<double>{q});
  // A version 1 file written before the back-driven map existed loads without it (c_b = 0: the
  // prior until the first push); one with only some of the four fields is refused. In version 2
  // every field is required.
  json old_file = files::to_json(observer_file());
  old_file["version"] = 1;
  for (const char* key : {"back_current_per_load", "back_current_offset",
                          "back_current_per_velocity", "back_variance", "load_per_angle"}) {
    old_file["parameters"].erase(key);
  }
  const auto q_old = files::joint_model_parameters<est::PushLoadObserverParameters<double>>(
      files::model_from_json(old_file));
  CHECK(q_old.back_current_per_load == 0.0);
  CHECK(q_old.load_per_angle == 0.0);
  CHECK(q_old.current_per_load == 1.45);
  json new_file = old_file;
  new_file["version"] = 2;
  CHECK(error_of(new_file) ==
        "model file m.json: parameters: missing field \"back_current_per_load\"");
  json partial = files::to_json(observer_file());
  partial["version"] = 1;
  partial["parameters"].erase("back_variance");
  CHECK(error_of(partial) ==
        "model file m.json: parameters: back_current_per_load, back_current_offset, "
        "back_current_per_velocity and back_variance go together (all four or none)");
  // The wrong kind, and the linear loaders, refuse with the kind named.
  CHECK(message_of(
            [&] { (void)files::joint_model_parameters<est::StallHoldParameters<double>>(o); }) ==
        "joint_model_parameters: the model file is of kind \"push_load_observer\", not "
        "\"stall_hold\"");
  CHECK(message_of([&] {
          (void)files::load_hammerstein_wiener<6, 2, 1>(dir.path() / "o.json");
        }).find("kind \"push_load_observer\" is a joint force model") != std::string::npos);
}

TEST_CASE(
    "joint-model files: the bidirectional observer round-trips and is checked field by field") {
  TempDir dir("bidirectional");
  files::save_model(dir.path() / "b.json", bidirectional_file());
  const files::ModelFile b = files::load_model(dir.path() / "b.json");
  CHECK(b.kind() == files::ModelKind::bidirectional_load_observer);
  CHECK(b.is_joint_model());
  CHECK(files::to_json(b) == files::to_json(bidirectional_file()));
  const json j = files::to_json(b);
  CHECK(j["parameters"]["stop_thresholds"].size() == 8);
  CHECK_FALSE(j["parameters"].contains("command_gain"));
  const auto q = files::joint_model_parameters<est::BidirectionalLoadObserverParameters<double>>(b);
  CHECK(q.forward_gain == -1.41e-3);
  CHECK(q.backward_offset_stroke == 0.035);
  CHECK(q.output_shape[7] == -0.78);
  CHECK(q.output_shape_per_load[7] == 0.089);
  CHECK(q.stop_thresholds[0] == 0.005);
  CHECK(q.sample_time == 0.001);
  CHECK_NOTHROW((void)est::BidirectionalLoadObserver<double>{q});
  // The parameters are the file's content: written back, the same file.
  CHECK(files::to_json(files::make_joint_model_file(q, clamp_inputs, {{"grip_torque", "mN m"}},
                                                    b.provenance)) == j);
  CHECK(message_of([&] {
          (void)files::joint_model_parameters<est::PushLoadObserverParameters<double>>(b);
        }) ==
        "joint_model_parameters: the model file is of kind "
        "\"bidirectional_load_observer\", not \"push_load_observer\"");
  // Hostile fields.
  auto with = [&](const char* key, const json& value) {
    json h = j;
    h["parameters"][key] = value;
    return h;
  };
  CHECK(error_of(with("stop_thresholds", json::array({0.1, 0.2}))) ==
        "model file m.json: field \"parameters.stop_thresholds\" must be an array of 8 numbers, "
        "got [0.1,0.2]");
  json unordered = j;
  unordered["parameters"]["stop_thresholds"][3] = 0.05;
  CHECK(error_of(unordered) ==
        "model file m.json: field \"parameters.stop_thresholds[3]\" must be above the "
        "threshold before it, got 0.05");
  json null_shape = j;
  null_shape["parameters"]["output_shape"][2] = nullptr;
  CHECK(error_of(null_shape) ==
        "model file m.json: field \"parameters.output_shape[2]\" is not a number (null)");
  json huge_shape = j;
  huge_shape["parameters"]["output_shape_per_load"][5] = 1e300;
  CHECK(error_of(huge_shape) ==
        "model file m.json: field \"parameters.output_shape_per_load[5]\" must be in [-1e6, "
        "1e6], got 1e+300");
  CHECK(error_of(with("forward_gain_stroke", 1.3e-3)) ==
        "model file m.json: field \"parameters.forward_gain_stroke\" must be at most 0.9 times "
        "the gain's magnitude (the gain keeps its sign and a tenth of its size along the stroke), "
        "got 0.0013");
  CHECK(error_of(with("backward_gain", 0.0)) ==
        "model file m.json: field \"parameters.backward_gain\" must be of magnitude in [1e-9, "
        "1e6], got 0");
  CHECK(error_of(with("backward_gain", 6.1e-4)) ==
        "model file m.json: field \"parameters.backward_gain\" must be of forward_gain's sign "
        "and at least 1e-6 times its magnitude (the current grows with the load both ways), got "
        "0.00061");
  CHECK(error_of(with("forward_variance", 1e-300)) ==
        "model file m.json: field \"parameters.forward_variance\" must be in [1e-12, 1e6], got "
        "1e-300");
  CHECK(error_of(with("friction_variance", -1.0)) ==
        "model file m.json: field \"parameters.friction_variance\" must be in [0, 1e6], got -1");
  CHECK(error_of(with("initial_load", 1e308)) ==
        "model file m.json: field \"parameters.initial_load\" must be in [-1e6, 1e6], got "
        "1e+308");
  CHECK(error_of(with("current_cutoff", 500.0)) ==
        "model file m.json: field \"parameters.current_cutoff\" must be in (0, Nyquist = 0.5 / "
        "sample_time) Hz, got 500");
  CHECK(error_of(with("push_sign", 1))
            .starts_with("model file m.json: unknown field \"parameters.push_sign\" for kind "
                         "\"bidirectional_load_observer\""));
  json missing = j;
  missing["parameters"].erase("output_shape");
  CHECK(error_of(missing) == "model file m.json: parameters: missing field \"output_shape\"");
  // The reference to the command: in version 1 both fields inside "parameters" or none, in
  // version 2 its own object; then a third input.
  json referred = with("command_gain", -2.02);
  referred["version"] = 1;
  CHECK(error_of(referred) ==
        "model file m.json: parameters: command_gain and reference_offset go together (both or "
        "none)");
  referred["parameters"]["reference_offset"] = -0.0175;
  CHECK(error_of(referred).find("needs 3 inputs") != std::string::npos);
  referred["inputs"].push_back({{"name", "current_command"}, {"unit", "1"}});
  const files::ModelFile with_command = files::model_from_json(referred, "m.json");
  const auto& ref = with_command.current_reference;
  REQUIRE(ref.has_value());
  CHECK(ref->command_gain == -2.02);
  json referred_v2 = files::to_json(with_command);
  CHECK(referred_v2["current_reference"] ==
        json{{"command_gain", -2.02}, {"reference_offset", -0.0175}});
  CHECK_FALSE(referred_v2["parameters"].contains("command_gain"));
  referred_v2["version"] = 1;
  referred_v2.erase("current_reference");
  referred_v2["parameters"]["command_gain"] = -2.02;
  referred_v2["parameters"]["reference_offset"] = -0.0175;
  CHECK(referred_v2 == referred);
  // The bridge has no command: refused there, saying why.
  write_text(dir.path() / "referred.json", referred.dump());
  write_text(dir.path() / "bridge.json", R"({"estimator": {"clamp_model": "referred.json"}})");
  CHECK(message_of([&] {
          (void)files::load_bridge_config(dir.path() / "bridge.json");
        }).find("the bidirectional_load_observer refers its current to the commanded current") !=
        std::string::npos);
  // A current reference on a kind without one.
  files::ModelFile stall = stall_hold_file();
  stall.current_reference = est::CurrentOffsetReferenceParameters<double>{};
  CHECK(message_of([&] { (void)files::to_json(stall); }) ==
        "to_json: kind \"stall_hold\" has no current_reference (only the observers refer their "
        "current to a command)");
}

// The model-file loader checks the estimation types' own bounds
// (model/joint_model_bounds.hpp).
static_assert(files::ModelFile::max_parameter == est::max_joint_model_parameter);
static_assert(files::ModelFile::min_current_per_load == est::min_current_per_load);

TEST_CASE("joint-model files: hostile and out-of-range content is refused naming the field") {
  const json good = files::to_json(stall_hold_file());
  auto with = [&](const char* key, const json& value) {
    json j = good;
    j["parameters"][key] = value;
    return j;
  };
  CHECK(error_of(with("current_deadzone", -0.1)) ==
        "model file m.json: field \"parameters.current_deadzone\" must be in [0, 1e6] A, got -0.1");
  CHECK(error_of(with("gain", nullptr)) ==
        "model file m.json: field \"parameters.gain\" is not a number (null)");
  CHECK(error_of(with("side", "up")) ==
        "model file m.json: field \"parameters.side\" is \"up\", expected \"both\", \"positive\" "
        "or \"negative\"");
  CHECK(error_of(with("velocity_threshold", "fast"))
            .find("\"parameters.velocity_threshold\" is "
                  "not a number") != std::string::npos);
  CHECK(error_of(with("spare", 1)) ==
        "model file m.json: unknown field \"parameters.spare\" for kind \"stall_hold\" (known: "
        "current_deadzone, velocity_threshold, velocity_time_constant, output_time_constant, "
        "gain, side)");
  json missing = good;
  missing["parameters"].erase("gain");
  CHECK(error_of(missing) == "model file m.json: parameters: missing field \"gain\"");
  json no_params = good;
  no_params.erase("parameters");
  CHECK(error_of(no_params) == "model file m.json: missing field \"parameters\"");
  json params_array = good;
  params_array["parameters"] = json::array();
  CHECK(error_of(params_array) == "model file m.json: field \"parameters\" is not an object");
  json linear = good;
  linear["A"] = json::array({json::array({0.5})});
  CHECK(error_of(linear) ==
        "model file m.json: kind \"stall_hold\" has no field \"A\" (its "
        "parameters are in \"parameters\")");
  json three = good;
  three["inputs"].push_back({{"name", "position"}, {"unit", "rad"}});
  CHECK(error_of(three) ==
        "model file m.json: kind \"stall_hold\" needs 2 inputs (current, "
        "velocity) and 1 output, got 3 and 1");
  json kind = good;
  kind["kind"] = "neural_network";
  CHECK(error_of(kind) ==
        "model file m.json: field \"kind\" is \"neural_network\", expected "
        "\"state_space\", \"hammerstein_wiener\", \"stall_hold\", "
        "\"push_load_observer\" or \"bidirectional_load_observer\"");
  json ts = good;
  ts["sample_time_s"] = 0.0;
  CHECK(error_of(ts) == "model file m.json: field \"sample_time_s\" must be finite and > 0, got 0");

  const json obs = files::to_json(observer_file());
  auto obs_with = [&](const char* key, const json& value) {
    json j = obs;
    j["parameters"][key] = value;
    return j;
  };
  CHECK(error_of(obs_with("push_sign", 0.5)) ==
        "model file m.json: field \"parameters.push_sign\" must be +1 or -1, got 0.5");
  CHECK(error_of(obs_with("current_cutoff", 600.0)) ==
        "model file m.json: field \"parameters.current_cutoff\" must be in (0, Nyquist = 0.5 / "
        "sample_time) Hz, got 600");
  CHECK(error_of(obs_with("measurement_variance", 0.0)) ==
        "model file m.json: field \"parameters.measurement_variance\" must be in (0, 1e6], got 0");
  CHECK(error_of(obs_with("current_per_load", 0.0)) ==
        "model file m.json: field \"parameters.current_per_load\" must be of magnitude in [1e-9, "
        "1e6], got 0");
  // Huge but finite values (before: loaded, then every tick's estimate was Inf and rejected).
  CHECK(error_of(obs_with("initial_load", 1e308)) ==
        "model file m.json: field \"parameters.initial_load\" must be in [-1e6, 1e6], got 1e+308");
  CHECK(error_of(obs_with("current_per_load", -1e-300)) ==
        "model file m.json: field \"parameters.current_per_load\" must be of magnitude in [1e-9, "
        "1e6], got -1e-300");
  CHECK(error_of(with("gain", -1e300)) ==
        "model file m.json: field \"parameters.gain\" must be in [-1e6, 1e6], got -1e+300");
  CHECK(error_of(obs_with("back_current_per_load", 1e-12)) ==
        "model file m.json: field \"parameters.back_current_per_load\" must be 0 or of magnitude "
        "in [1e-9, 1e6], got 1e-12");
  CHECK(error_of(obs_with("back_variance", 0.0)) ==
        "model file m.json: field \"parameters.back_variance\" must be in (0, 1e6], got 0");
  // Beyond the joint-model bound of docs/rig.md (before: accepted).
  CHECK(error_of(obs_with("direction_scale", 1e308)) ==
        "model file m.json: field \"parameters.direction_scale\" must be in (0, 1e6] rad, got "
        "1e+308");
  CHECK(error_of(obs_with("velocity_threshold", 1e308)) ==
        "model file m.json: field \"parameters.velocity_threshold\" must be in [0, 1e6] rad/s, got "
        "1e+308");
  CHECK(error_of(obs_with("back_current_offset", -1e300)) ==
        "model file m.json: field \"parameters.back_current_offset\" must be in [-1e6, 1e6], got "
        "-1e+300");
  CHECK(error_of(obs_with("direction_threshold", 1.5)) ==
        "model file m.json: field \"parameters.direction_threshold\" must be in (0, 1], got 1.5");
  // The library's maker checks the same rules (the type's own).
  est::StallHoldParameters<double> bad;
  bad.output_time_constant = std::numeric_limits<double>::infinity();
  CHECK(message_of([&] {
          (void)files::make_joint_model_file(bad, clamp_inputs, {{"force", "N"}});
        }) ==
        "make_joint_model_file: field \"parameters.output_time_constant\" must be in [0, 1e6] s, "
        "got inf");
  // The stiffness and the current's offset reference (a third input, the command).
  CHECK(error_of(obs_with("load_per_angle", 1e300)) ==
        "model file m.json: field \"parameters.load_per_angle\" must be in [-1e6, 1e6], got "
        "1e+300");
  json half_reference = obs;
  half_reference["version"] = 1;
  half_reference["parameters"]["command_gain"] = -2.06;
  CHECK(error_of(half_reference) ==
        "model file m.json: parameters: command_gain and reference_offset go together (both or "
        "none)");
  json two_inputs = half_reference;
  two_inputs["parameters"]["reference_offset"] = -0.005;
  CHECK(error_of(two_inputs) ==
        "model file m.json: kind \"push_load_observer\" needs 3 inputs (current, velocity, "
        "current command: its command_gain is not 0) and 1 output, got 2 and 1");
  json with_command = two_inputs;
  with_command["inputs"].push_back({{"name", "current_command"}, {"unit", "1"}});
  const files::ModelFile referred = files::model_from_json(with_command, "m.json");
  const auto& ref = referred.current_reference;
  REQUIRE(ref.has_value());
  CHECK(ref->command_gain == -2.06);
  CHECK(ref->reference_offset == -0.005);
  CHECK(files::model_from_json(files::to_json(referred)).current_reference->command_gain == -2.06);
  CHECK_FALSE(files::model_from_json(obs).current_reference.has_value());
  json zero_gain = files::to_json(referred);
  zero_gain["current_reference"]["command_gain"] = 1e-12;
  CHECK(error_of(zero_gain) ==
        "model file m.json: field \"current_reference.command_gain\" must be of magnitude in "
        "[1e-9, 1e6], got 1e-12");
  json stray = files::to_json(referred);
  stray["current_reference"]["gain"] = 1.0;
  CHECK(error_of(stray) ==
        "model file m.json: unknown field \"current_reference.gain\" (known: command_gain, "
        "reference_offset)");
  // The bridge has no command: such a model is refused there, saying why.
  TempDir dir("joint_reference");
  write_text(dir.path() / "referred.json", with_command.dump());
  write_text(dir.path() / "bridge.json", R"({"estimator": {"clamp_model": "referred.json"}})");
  CHECK(message_of([&] { (void)files::load_bridge_config(dir.path() / "bridge.json"); })
            .find("refers its current to the commanded current (a third input), which the sbRIO "
                  "protocol does not carry") != std::string::npos);
}

TEST_CASE("model files: the version 1 files in the repository load, and write back as version 2") {
  // The seeds of the model-file fuzz target: one file of each kind, written as version 1.
  const std::filesystem::path corpus =
      std::filesystem::path(__FILE__).parent_path().parent_path() / "fuzz" / "corpus";
  int loaded = 0;
  for (const char* kind : {"state_space", "hammerstein_wiener", "stall_hold", "push_load_observer",
                           "bidirectional_load_observer"}) {
    for (const auto& entry :
         std::filesystem::directory_iterator(corpus / ("model_file_" + std::string(kind)))) {
      CAPTURE(entry.path());
      const files::ModelFile m = files::load_model(entry.path());
      CHECK(files::to_string(m.kind()) == kind);
      const json written = files::to_json(m);
      CHECK(written["version"] == 2);
      CHECK(files::to_json(files::model_from_json(written)) == written);
      ++loaded;
    }
  }
  CHECK(loaded >= 5);
}

TEST_CASE("bridge: a model file of each kind configures the clamps and runs in the tick") {
  TempDir dir("bridge_joint");
  files::save_model(dir.path() / "stall.json", stall_hold_file());
  files::save_model(dir.path() / "observer.json", observer_file());
  files::save_model(dir.path() / "bidirectional.json", bidirectional_file());
  for (const char* name : {"stall.json", "observer.json", "bidirectional.json"}) {
    CAPTURE(name);
    write_text(dir.path() / "bridge.json",
               std::string(R"({"estimator": {"clamp_model": ")") + name + "\"}}");
    const files::BridgeConfig config = files::load_bridge_config(dir.path() / "bridge.json");
    const est::BridgeForceModels models =
        est::bridge_force_models(files::load_bridge_joint_model(config.clamp_model));
    CHECK(models.clamp1.index() != 0);
    CHECK(models.clamp1.get<est::ClampModel2016<double>>() == nullptr);
    auto settings = est::bridge_estimator_settings(config.estimator, models);
    // The joint models hold their own friction: the 5.2.3 gate of the clamps is opened.
    CHECK(settings.friction[2].static_level == 0.0);
    CHECK(settings.friction[3].static_level == 0.0);
    CHECK(settings.friction[0].static_level == 0.7);  // roll untouched
    est::BridgeForceEstimator estimator(models, settings);
    CHECK(estimator.ticks_per_model_step(est::Motor::clamp1) ==
          (std::string(name) == "stall.json" ? 10 : 1));
    est::JointState<double> in;
    est::ForceEstimator<>::Forces out = est::ForceEstimator<>::Forces::Zero();
    // A grasp: the clamp-1 motor closes with rising negative current, then stalls.
    bool ok = true;
    const long allocations = endohaptics::test::allocations_during([&] {
      for (int k = 0; k < 2000; ++k) {
        const double t = 1e-3 * k;
        in.velocity[2] = t < 1.0 ? 0.1 : 0.0;
        in.position[2] += 1e-3 * in.velocity[2];
        in.current[2] = t < 1.0 ? -0.8 * t : -0.8 * std::exp(-(t - 1.0) / 0.2);
        ok = ok && estimator.step(in, out) == est::NumericStatus::ok;
      }
    });
    CHECK(ok);
    CHECK(allocations == 0);
    CHECK(out.allFinite());
    if (std::string(name) == "stall.json") {
      // Held through the stall although the current has relaxed to -0.005 A (far below the
      // 0.18 A dead zone and the 0.21 A friction gate): about gain x (0.7 - 0.18) A.
      CHECK(std::abs(in.current[2]) < 0.01);
      CHECK(std::abs(out[2]) > 3.0);
      CHECK(std::abs(out[2]) < 7.5 * 0.62);
    }
    // The estimator's reset restarts the models as constructed (the observer: its initial
    // load, not a zero state with zero variance).
    // (The state after the reset is the state of the model as constructed from the file.)
    estimator.reset();
    CHECK(estimator.joint_model<est::Motor::clamp1>().state() == models.clamp1.state());
    // A snapshot restores the model exactly (a failed tick leaves the estimator untouched).
    est::BridgeJointModel model = models.clamp1;
    for (int k = 0; k < 30; ++k) (void)model.advance({0.001 * k, 0.1, -0.02 * k, 0.0});
    const est::BridgeJointModel::State saved = model.state();
    (void)model.advance({0.05, 0.1, -0.7, 0.0});
    model.reset(saved);
    CHECK(model.state() == saved);
    if (const auto* o =
            estimator.joint_model<est::Motor::clamp1>().get<est::PushLoadObserver<double>>()) {
      CHECK(o->state()[6] == 0.04);
      CHECK(o->state()[7] == o->parameters().initial_variance);
    }
    if (const auto* b = estimator.joint_model<est::Motor::clamp1>()
                            .get<est::BidirectionalLoadObserver<double>>()) {
      CHECK(b->load_estimate() == -65.8);
      CHECK(b->state()[est::BidirectionalLoadObserver<double>::p_ff] == 62.0);
    }
  }
}

}  // namespace files_joint_model_file_test
