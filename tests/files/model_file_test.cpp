#include "endohaptics/files/model_file.hpp"

#include <doctest/doctest.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <random>
#include <string>
#include <type_traits>

#include "endohaptics/estimation/force_estimator.hpp"
#include "endohaptics/files/identified_model_file.hpp"
#include "endohaptics/identification/fit_metrics.hpp"
#include "endohaptics/identification/subspace.hpp"
#include "endohaptics/model/presets_2016.hpp"
#include "test_support.hpp"

namespace files_model_file_test {

using endohaptics::test::message_of;
using endohaptics::test::TempFile;
using endohaptics::test::write_text;

namespace {

namespace id = endohaptics::identification;
namespace files = endohaptics::files;
namespace est = endohaptics::estimation;
namespace model = endohaptics::model;
using Eigen::MatrixXd;
using Eigen::VectorXd;
using endohaptics::Error;
using nlohmann::json;

const std::vector<files::SignalInfo> yaw_inputs{{"current", "A"}, {"velocity", "rad/s"}};
const std::vector<files::SignalInfo> yaw_outputs{{"force", "N"}};

// A valid 2-state, 1-input, 1-output model as JSON, to break one field at a time.
json valid_json() {
  files::ModelFile f{.state_space = model::DynamicStateSpace<>(
                         MatrixXd{{0.9, 0.1}, {0.0, 0.5}}, MatrixXd{{1.0}, {0.5}},
                         MatrixXd{{1.0, 0.0}}, MatrixXd::Zero(1, 1), 0.02),
                     .inputs = {{"current", "A"}},
                     .outputs = {{"force", "N"}},
                     .input_nonlinearity = {{model::StaticMapKind::deadzone, -0.2, 0.2}},
                     .output_nonlinearity = {{}},
                     .provenance = {.method = "moesp", .date = "2016-05-01"}};
  return files::to_json(f);
}

}  // namespace

TEST_CASE("an identified model round-trips through a file bit for bit, with provenance") {
  std::mt19937 rng(5);
  std::normal_distribution<double> normal;
  MatrixXd u(600, 2);
  for (Eigen::Index i = 0; i < u.size(); ++i) u.data()[i] = normal(rng);
  const model::DynamicStateSpace<> truth(MatrixXd{{0.9, 0.3}, {-0.3, 0.9}},
                                         MatrixXd{{1.0, -0.2}, {0.4, 0.3}}, MatrixXd{{1.0, -0.5}},
                                         MatrixXd::Zero(1, 2), 0.02);
  const MatrixXd y = id::simulate(truth, u, VectorXd::Zero(2));
  id::SubspaceOptions options;
  options.sample_time = 0.02;
  const auto m = id::identify(u, y, options);

  files::ModelProvenance provenance;
  provenance.files = {"yaw_grip_01.csv", "yaw_grip_02.csv"};
  provenance.fit_percent = {id::compare(m, u, y).fit[0]};
  provenance.notes = "synthetic";
  const files::ModelFile file = files::make_model_file(m, yaw_inputs, yaw_outputs, provenance);
  CHECK(file.provenance.method == "moesp");
  CHECK(file.provenance.order == 2);
  CHECK(file.provenance.block_rows == 15);
  CHECK(file.provenance.date.size() == 10);  // YYYY-MM-DD, today (UTC)

  TempFile tmp("roundtrip.json");
  files::save_model(tmp.path, file);
  const files::ModelFile back = files::load_model(tmp.path);
  CHECK(file.state_space.A() == m.state_space.A());  // the identified model, unchanged
  CHECK(file.state_space.state() == m.initial_states[0]);
  CHECK(back.state_space.A() == file.state_space.A());  // shortest round-trip decimal: bit-exact
  CHECK(back.state_space.B() == file.state_space.B());
  CHECK(back.state_space.C() == file.state_space.C());
  CHECK(back.state_space.D() == file.state_space.D());
  CHECK(back.state_space.state() == file.state_space.state());
  CHECK(back.state_space.sample_time() == 0.02);
  CHECK(back.inputs[1].name == "velocity");
  CHECK(back.inputs[1].unit == "rad/s");
  CHECK(back.outputs[0].unit == "N");
  CHECK(back.provenance.files == provenance.files);
  CHECK(back.provenance.fit_percent == provenance.fit_percent);
  CHECK(back.provenance.notes == "synthetic");
  CHECK(back.provenance.date == file.provenance.date);
  CHECK_FALSE(back.is_hammerstein_wiener());
  const json j = json::parse(std::ifstream(tmp.path));
  CHECK(j.at("kind") == "state_space");
  CHECK(j.at("states") == 2);
  CHECK_FALSE(j.contains("input_nonlinearity"));

  auto ss = files::load_state_space<2, 2, 1>(tmp.path);
  CHECK(ss.sample_time() == 0.02);
  CHECK(ss.state() == Eigen::Vector2d(m.state_space.state()));
  const auto ssf = files::load_state_space<2, 2, 1, float>(tmp.path);
  CHECK(ssf.A()(0, 0) == static_cast<float>(m.state_space.A()(0, 0)));
  CHECK(message_of([&] { (void)files::load_state_space<4, 2, 1>(tmp.path); }) ==
        "model file " + tmp.path.string() +
            ": StateSpace: cannot convert a model with 2 states, 2 inputs, 1 outputs into "
            "StateSpace<4, 2, 1>");
}

TEST_CASE("a loaded yaw Hammerstein-Wiener model drives OpenLoop and the ForceEstimator") {
  // The appendix C yaw model with the 0.21 A dead zone, saved and loaded again.
  const auto preset = model::yaw_force_2016_hw();
  files::ModelProvenance provenance;
  provenance.method = "worksheet appendix C (MATLAB n4sid + idDeadZone)";
  provenance.date = "2016-06-01";
  TempFile tmp("yaw_hw.json");
  files::save_model(tmp.path, files::make_model_file(preset, yaw_inputs, yaw_outputs, provenance));
  const files::ModelFile file = files::load_model(tmp.path);
  REQUIRE(file.is_hammerstein_wiener());
  CHECK(file.input_nonlinearity[0].kind == model::StaticMapKind::deadzone);
  CHECK(file.input_nonlinearity[0].upper == 0.21);
  CHECK(file.input_nonlinearity[1].upper == 0.0);
  CHECK(file.output_nonlinearity[0].kind == model::StaticMapKind::none);

  auto loaded = files::load_hammerstein_wiener<6, 2, 1>(tmp.path);
  static_assert(std::is_same_v<decltype(loaded), model::YawForceHW2016<double>>,
                "the default loader gives the yaw preset's own type");
  CHECK(loaded.linear().A() == preset.linear().A());
  CHECK(loaded.input_nonlinearity().channel(0).lower() == -0.21);

  // OpenLoop on the loaded model = OpenLoop on the preset.
  est::OpenLoop<model::YawForceHW2016<double>> from_file(loaded);
  est::OpenLoop<model::YawForceHW2016<double>> from_preset(preset);
  for (int k = 0; k < 200; ++k) {
    const est::JointSignals<double> s{0.0, 1.5 * std::sin(0.03 * k), 0.5 * std::sin(0.02 * k), 0.0};
    REQUIRE(from_file.force(s) == from_preset.force(s));
    REQUIRE(from_file.advance(s) == model::NumericStatus::ok);
    REQUIRE(from_preset.advance(s) == model::NumericStatus::ok);
  }
  CHECK(from_file.force({0.0, 0.5, 0.6, 0.0}) != 0.0);

  // Clamp 1 of a ForceEstimator from the file: the same forces as the 2016 defaults, whose
  // clamp 1 is this preset with 0.21 A (clamp 2 keeps its default 0.20 A preset).
  auto models = est::models_2016<double>();
  models.clamp1 = est::ClampModel2016<double>(loaded);
  est::ForceEstimator<est::rate::Decimate> with_file(models, {});
  est::ForceEstimator<est::rate::Decimate> defaults;
  est::JointState<double> in;
  est::ForceEstimator<est::rate::Decimate>::Forces f_file;
  est::ForceEstimator<est::rate::Decimate>::Forces f_default;
  double largest = 0.0;
  for (int k = 0; k < 400; ++k) {
    in.current = Eigen::Vector4d::Constant(0.8 * std::sin(0.004 * k));
    in.velocity = Eigen::Vector4d::Constant(std::cos(0.004 * k));
    REQUIRE(with_file.step(in, f_file) == est::NumericStatus::ok);
    REQUIRE(defaults.step(in, f_default) == est::NumericStatus::ok);
    REQUIRE(f_file == f_default);
    largest = std::max(largest, std::abs(f_file[2]));
  }
  CHECK(largest > 0.0);  // the clamp estimate is not trivially zero
}

TEST_CASE("a free-motion threshold round-trips, and is refused negative or on a joint model") {
  files::ModelFile file =
      files::make_model_file(model::yaw_force_2016_hw(0.1), yaw_inputs, yaw_outputs);
  const TempFile f("free_threshold.json");
  files::save_model(f.path, file);
  CHECK(files::load_model(f.path).free_motion_threshold == 0.0);  // absent: none
  file.free_motion_threshold = 0.125;
  files::save_model(f.path, file);
  CHECK(files::load_model(f.path).free_motion_threshold == 0.125);
  file.free_motion_threshold = -0.1;
  CHECK(message_of([&] {
          files::save_model(f.path, file);
        }).find("free_motion_threshold must be in [0, ") != std::string::npos);
  nlohmann::json joint = files::to_json(
      files::make_joint_model_file(est::StallHoldParameters<double>{}, yaw_inputs, yaw_outputs));
  joint["free_motion_threshold"] = 0.1;
  write_text(f.path, joint.dump());
  CHECK(message_of([&] {
          (void)files::load_model(f.path);
        }).find("has no field \"free_motion_threshold\"") != std::string::npos);
}

TEST_CASE("a current play round-trips, and is refused negative or on a joint model") {
  files::ModelFile file =
      files::make_model_file(model::yaw_force_2016_hw(0.1), yaw_inputs, yaw_outputs);
  const TempFile f("current_play.json");
  files::save_model(f.path, file);
  CHECK(files::load_model(f.path).current_play == 0.0);  // absent: none
  CHECK_FALSE(files::to_json(file).contains("current_play"));
  file.current_play = 0.17;
  files::save_model(f.path, file);
  CHECK(files::load_model(f.path).current_play == 0.17);
  file.current_play = -0.1;
  CHECK(message_of([&] { files::save_model(f.path, file); }).find("current_play must be in [0, ") !=
        std::string::npos);
  nlohmann::json joint = files::to_json(
      files::make_joint_model_file(est::StallHoldParameters<double>{}, yaw_inputs, yaw_outputs));
  joint["current_play"] = 0.1;
  write_text(f.path, joint.dump());
  CHECK(message_of([&] {
          (void)files::load_model(f.path);
        }).find("has no field \"current_play\"") != std::string::npos);
}

TEST_CASE("a friction play round-trips, and is refused outside its play or without one") {
  // The demo's roll (model::friction_play): sticks at 0.13 A, slides at 0.065 A plus -0.025 A s/rad
  // times the velocity (input 1).
  files::ModelFile file =
      files::make_model_file(model::yaw_force_2016_hw(0.1), yaw_inputs, yaw_outputs);
  const TempFile f("friction_play.json");
  file.current_play = 0.13;
  files::save_model(f.path, file);
  const files::ModelFile plain = files::load_model(f.path);
  CHECK_FALSE(plain.current_play_slide.has_value());  // absent: slides at the play
  CHECK(plain.current_play_viscous == 0.0);
  CHECK_FALSE(files::to_json(file).contains("current_play_slide"));
  CHECK_FALSE(files::to_json(file).contains("current_play_viscous"));
  file.current_play_slide = 0.065;
  file.current_play_viscous = -0.025;
  files::save_model(f.path, file);
  const files::ModelFile back = files::load_model(f.path);
  REQUIRE(back.current_play_slide.has_value());
  CHECK(*back.current_play_slide == 0.065);
  CHECK(back.current_play_viscous == -0.025);
  CHECK(files::to_json(back) == files::to_json(file));
  const auto refused = [&](files::ModelFile m) {
    return message_of([&] { files::save_model(f.path, m); });
  };
  auto wide = file;
  wide.current_play_slide = 0.2;
  CHECK(refused(wide).find("current_play_slide must be in [0, current_play = 0.13], got 0.2") !=
        std::string::npos);
  auto none = file;
  none.current_play = 0.0;
  none.current_play_slide.reset();
  CHECK(refused(none).find("current_play_slide and current_play_viscous need a current_play") !=
        std::string::npos);
  auto nan = file;
  nan.current_play_viscous = std::nan("");
  CHECK(refused(nan).find("current_play_viscous must be finite") != std::string::npos);
}

TEST_CASE("load errors name the file, the field and the value") {
  const std::string src = "model file test";
  auto broken = [](auto edit) {
    json j = valid_json();
    edit(j);
    return message_of([&] { (void)files::model_from_json(j, "test"); });
  };
  CHECK(files::model_from_json(valid_json(), "test").is_hammerstein_wiener());
  CHECK(broken([](json& j) { j.erase("C"); }) == src + ": missing field \"C\"");
  CHECK(broken([](json& j) { j.erase("sample_time_s"); }) ==
        src + ": missing field \"sample_time_s\"");
  CHECK(broken([](json& j) { j["provenance"].erase("date"); }) ==
        src + ": provenance: missing field \"date\"");
  CHECK(broken([](json& j) { j["B"].push_back(json::array({1.0})); }) ==
        src + ": field \"B\" has 3 rows, expected 2 (states)");
  CHECK(broken([](json& j) {
          j["A"][1] = json::array({1.0, 2.0, 3.0});
        }) == src + ": field \"A[1]\" has 3 columns, expected 2 (states)");
  CHECK(broken([](json& j) { j["x0"] = json::array({0.0}); }) ==
        src + ": field \"x0\" must be an array of 2 numbers (states), got [0.0]");
  // NaN: nlohmann writes NaN as null; a null entry is refused by name.
  CHECK(broken([](json& j) { j["A"][1][0] = std::nan(""); }) ==
        src + ": field \"A[1][0]\" is not finite (nan)");
  CHECK(broken([](json& j) {
          j["A"][1][0] = std::nan("");
          j = json::parse(j.dump());  // as written to a file
        }) == src + ": field \"A[1][0]\" is not a number (null)");
  CHECK(broken([](json& j) { j["sample_time_s"] = -0.02; }) ==
        src + ": field \"sample_time_s\" must be finite and > 0, got -0.02");
  CHECK(broken([](json& j) { j["input_nonlinearity"][0]["lower"] = 0.5; }) ==
        src + ": field \"input_nonlinearity[0]\": lower 0.5 is greater than upper 0.2");
  CHECK(broken([](json& j) { j["input_nonlinearity"][0]["type"] = "relay"; }) ==
        src +
            ": field \"input_nonlinearity[0].type\" is \"relay\", expected none, deadzone or "
            "saturation");
  CHECK(broken([](json& j) { j["output_nonlinearity"] = json::array(); }) ==
        src + ": field \"output_nonlinearity\" has 0 entries, expected 1 (outputs)");
  CHECK(broken([](json& j) { j["version"] = 3; }) ==
        src + ": field \"version\" is 3, expected 1 or 2");
  CHECK(broken([](json& j) { j["kind"] = "arx"; }) ==
        src +
            ": field \"kind\" is \"arx\", expected \"state_space\", \"hammerstein_wiener\", "
            "\"stall_hold\", \"push_load_observer\" or \"bidirectional_load_observer\"");
  CHECK(broken([](json& j) { j["inputs"][0].erase("unit"); }) ==
        src + ": inputs[0]: missing field \"unit\"");

  // Files: unreadable, not JSON (a bare NaN literal is not JSON), a type the loader cannot hold.
  CHECK(message_of([] { (void)files::load_model("/nonexistent/model.json"); }) ==
        "model file '/nonexistent/model.json' cannot be opened: the file does not exist");
  TempFile tmp("errors.json");
  std::string text = valid_json().dump();
  text.replace(text.find("0.9"), 3, "NaN");
  write_text(tmp.path, text);
  const std::string nan_message = message_of([&] { (void)files::load_model(tmp.path); });
  CHECK(nan_message.find("model file " + tmp.path.string() +
                         ": not valid JSON: parse error at line 1") == 0);
  write_text(tmp.path, valid_json().dump());
  CHECK(message_of([&] {
          (void)files::load_hammerstein_wiener<2, 1, 1, double, model::Saturation<double>>(
              tmp.path);
        }) == "model file " + tmp.path.string() +
                  ": to_hammerstein_wiener: input 0 is a deadzone, which the requested "
                  "nonlinearity type cannot represent");
  const auto hw = files::load_hammerstein_wiener<2, 1, 1>(tmp.path);
  CHECK(hw.input_nonlinearity().channel(0).upper() == 0.2);
}

TEST_CASE("saving refuses a NaN state and mismatched signal or map counts, naming the field") {
  files::ModelFile f = files::model_from_json(valid_json());
  f.state_space.reset(Eigen::VectorXd{{0.0, std::nan("")}});
  CHECK(message_of([&] { (void)files::to_json(f); }) ==
        "to_json: field \"x0[1]\" is not finite (nan)");
  f = files::model_from_json(valid_json());
  f.inputs.push_back({"velocity", "rad/s"});
  CHECK(message_of([&] { (void)files::to_json(f); }) ==
        "to_json: field \"inputs\" has 2 entries, the model has 1 inputs (columns of B)");
  f = files::model_from_json(valid_json());
  f.output_nonlinearity.push_back({});
  CHECK(message_of([&] { (void)files::to_json(f); }) ==
        "to_json: field \"output_nonlinearity\" has 2 entries, expected 1 (outputs)");
  f = files::model_from_json(valid_json());
  TempFile tmp("save_errors.json");
  CHECK(message_of([&] { files::save_model("/nonexistent/dir/model.json", f); }) ==
        "save_model: cannot open /nonexistent/dir/model.json for writing");
  // make_model_file refuses signal counts that differ from the model's sizes.
  CHECK(
      message_of([] {
        (void)files::make_model_file(model::yaw_force_2016(), {{"current", "A"}}, {{"force", "N"}});
      }) ==
      "make_model_file: field \"inputs\" has 1 entries, the model has 2 inputs (columns "
      "of B)");
}

TEST_CASE("hostile model files: deep nesting, duplicate keys, huge values are refused, bounded") {
  // Before: 80,000 nested arrays crashed replay --model (the error path dumped the value).
  TempFile tmp("hostile.json");
  write_text(tmp.path, "{\"states\": " + std::string(80000, '[') + std::string(80000, ']') + "}");
  const std::string deep = message_of([&] { (void)files::load_model(tmp.path); });
  CHECK(deep.find(": nested deeper than 32 levels (the limit; a model file needs 4)") !=
        std::string::npos);
  // A value nested within the limit is echoed in at most 60 characters (12 levels of doubling:
  // 4096 empty arrays, 16 KB of text; 20 levels took 30 s in the sanitized -O0 test build).
  json j = valid_json();
  json nested = json::array();
  for (int i = 0; i < 12; ++i) nested = json::array({nested, nested});
  j["states"] = nested;
  write_text(tmp.path, j.dump());
  const std::string echoed = message_of([&] { (void)files::load_model(tmp.path); });
  CHECK(echoed.find("field \"states\"") != std::string::npos);
  CHECK(echoed.size() < 300);
  // Duplicate keys: never "the last one wins".
  std::string dup = valid_json().dump();
  dup.insert(1, "\"version\": 1, ");
  write_text(tmp.path, dup);
  CHECK(message_of([&] {
          (void)files::load_model(tmp.path);
        }).find("duplicate key 'version' (a key may appear only once)") != std::string::npos);
}

}  // namespace files_model_file_test
