// One model set per instrument (files/model_set_file.hpp): the set file and directory forms,
// the choice by instrument name through the bridge configuration, and what they refuse.
#include "endohaptics/files/model_set_file.hpp"

#include <doctest/doctest.h>

#include <filesystem>
#include <string>

#include "endohaptics/estimation/stall_hold.hpp"
#include "endohaptics/files/bridge_config.hpp"
#include "endohaptics/files/model_file.hpp"
#include "endohaptics/model/presets_2016.hpp"
#include "test_support.hpp"

namespace files_model_set_test {

using endohaptics::test::message_of;
using endohaptics::test::TempDir;
using endohaptics::test::write_text;

namespace {

namespace files = endohaptics::files;
namespace est = endohaptics::estimation;
using endohaptics::protocol::Motor;

const std::vector<files::SignalInfo> clamp_inputs{{"current", "A"}, {"velocity", "rad/s"}};

// A stall-hold clamp model file, as endohaptics-identify saves it.
void save_stall_hold(const std::filesystem::path& path) {
  est::StallHoldParameters<double> p;
  p.gain = -7.5;
  p.side = est::StallHoldSide::negative;
  p.current_deadzone = 0.18;
  p.sample_time = 0.01;
  files::save_model(path, files::make_joint_model_file(p, clamp_inputs, {{"force", "N"}},
                                                       {.method = "stall_hold"}));
}

// The appendix C yaw model with a 0.3 A dead zone as a Hammerstein-Wiener model file.
void save_yaw(const std::filesystem::path& path) {
  files::save_model(path, files::make_model_file(endohaptics::model::yaw_force_2016_hw(0.3),
                                                 clamp_inputs, {{"force", "N"}}));
}

const std::array<bool, 4> all_fed = {true, true, true, true};

}  // namespace

TEST_CASE("model set: a set file loads, its clamps differ and the description names them") {
  const TempDir dir("model_set");
  save_stall_hold(dir.path() / "c1.json");
  save_yaw(dir.path() / "c2.json");
  write_text(dir.path() / "EW1.json", R"({"format": "endohaptics model set", "format_version": 1,
    "instrument": "EW1",
    "models": {"clamp1": "c1.json", "clamp2": "c2.json", "roll": "preset:roll2016",
               "pitch": "preset:pitch2016"}})");
  const files::ModelSet set = files::load_instrument_model_set(dir.path(), "EW1");
  CHECK(set.instrument == "EW1");
  CHECK(set.model(Motor::clamp1) == (dir.path() / "c1.json").string());
  CHECK(set.model(Motor::roll) == "preset:roll2016");
  const files::BridgeModelSet b = files::bridge_model_set(set, all_fed);
  CHECK(b.models.clamp1.get<est::StallHold<double>>() != nullptr);
  const auto* yaw = b.models.clamp2.get<est::IdentifiedHammersteinWiener<double>>();
  REQUIRE(yaw != nullptr);
  CHECK(yaw->model().input_nonlinearity().channel(0).upper() == 0.3);
  CHECK(b.description == "instrument EW1 (model set " + (dir.path() / "EW1.json").string() +
                             "): clamp1 stall_hold (" + (dir.path() / "c1.json").string() +
                             "), clamp2 hammerstein_wiener (" + (dir.path() / "c2.json").string() +
                             "), roll preset:roll2016, pitch preset:pitch2016");
  // The friction gate and the 2016 unit scale belong to the 2016 models: opened for both clamps
  // (a joint model, an identified model), kept for roll and pitch (their presets).
  const auto settings = est::bridge_estimator_settings({}, b.models);
  const est::ForceEstimatorSettings<double> preset{};
  CHECK(settings.friction[static_cast<std::size_t>(Motor::clamp1)].static_level == 0.0);
  CHECK(settings.friction[static_cast<std::size_t>(Motor::clamp2)].static_level == 0.0);
  CHECK(settings.friction[static_cast<std::size_t>(Motor::roll)].static_level ==
        preset.friction[0].static_level);
  CHECK(settings.unit_scale[static_cast<int>(Motor::pitch)] == preset.unit_scale[1]);
}

TEST_CASE("model set: roll and pitch take identified model files, without the 2016 gate and unit") {
  const TempDir dir("model_set");
  std::filesystem::create_directories(dir.path() / "EW3");
  for (const char* m : {"roll", "pitch", "clamp1", "clamp2"}) {
    files::ModelFile file =
        files::make_model_file(endohaptics::model::yaw_force_2016_hw(0.1),
                               {{"current", "A"}, {"velocity", "rad/s"}}, {{"force", "N"}});
    file.free_motion_threshold = std::string(m) == "roll" ? 0.05 : 0.0;
    files::save_model(dir.path() / "EW3" / (std::string(m) + ".json"), file);
  }
  const files::ModelSet set = files::load_instrument_model_set(dir.path(), "EW3");
  const files::BridgeModelSet b = files::bridge_model_set(set, all_fed);
  REQUIRE(b.models.roll.get<est::IdentifiedHammersteinWiener<double>>() != nullptr);
  // The file's free-motion threshold runs in the bridge: a force below it reads 0.
  const auto* roll = b.models.roll.get<est::IdentifiedHammersteinWiener<double>>();
  CHECK(roll->threshold().threshold() == 0.05);
  CHECK(b.models.pitch.get<est::IdentifiedHammersteinWiener<double>>()->threshold().threshold() ==
        0.0);
  CHECK(b.models.pitch.get<est::IdentifiedHammersteinWiener<double>>() != nullptr);
  const auto settings = est::bridge_estimator_settings({}, b.models);
  for (int j = 0; j < 4; ++j) {
    CHECK(settings.friction[static_cast<std::size_t>(j)].static_level == 0.0);
    CHECK(settings.unit_scale[j] == 1.0);  // the pitch preset's gram-force is not the file's N
    CHECK(settings.output_limit[j] == doctest::Approx(9.80665));  // not roll's 0.084 N m
  }
  // The defaults keep the 2016 settings on every joint.
  const auto defaults = est::bridge_estimator_settings({}, est::bridge_force_models());
  CHECK(defaults.unit_scale[static_cast<int>(Motor::pitch)] == doctest::Approx(9.80665e-3));
  CHECK(defaults.friction[static_cast<std::size_t>(Motor::roll)].static_level ==
        doctest::Approx(0.7));
}

TEST_CASE("model set: a directory of <motor>.json files loads, named by the directory") {
  const TempDir dir("model_set");
  std::filesystem::create_directory(dir.path() / "EW2");
  save_stall_hold(dir.path() / "EW2" / "clamp1.json");
  save_stall_hold(dir.path() / "EW2" / "clamp2.json");
  const files::ModelSet set = files::load_instrument_model_set(dir.path(), "EW2");
  CHECK(set.instrument == "EW2");
  CHECK(set.model(Motor::roll).empty());
  // Roll and pitch fed back but not in the set: refused, both named.
  const std::string missing = message_of([&] { (void)files::bridge_model_set(set, all_fed); });
  CHECK(missing.find("no model for roll, pitch,") != std::string::npos);
  CHECK(missing.find("instrument 'EW2'") != std::string::npos);
  // Without their feedback they run the 2016 presets, and the description says so.
  std::array<bool, 4> clamps_only{};
  clamps_only[static_cast<std::size_t>(Motor::clamp1)] = true;
  clamps_only[static_cast<std::size_t>(Motor::clamp2)] = true;
  const files::BridgeModelSet b = files::bridge_model_set(set, clamps_only);
  CHECK(b.models.clamp2.get<est::StallHold<double>>() != nullptr);
  CHECK(b.description.ends_with(
      "roll preset:roll2016 (none in the set, no force feedback), pitch preset:pitch2016 (none "
      "in the set, no force feedback)"));
  // A set file in the directory is the set.
  write_text(dir.path() / "EW2" / "model_set.json",
             R"({"format": "endohaptics model set", "format_version": 1, "instrument": "EW2",
                 "models": {"clamp1": "clamp1.json", "clamp2": "preset:clamp2016-as-run"}})");
  const files::BridgeModelSet d =
      files::bridge_model_set(files::load_instrument_model_set(dir.path(), "EW2"), clamps_only);
  CHECK(d.models.clamp2.get<est::Clamp2016AsRun<double>>() != nullptr);
}

TEST_CASE("model set: refusals name the file and the field") {
  const TempDir dir("model_set");
  const auto error_of = [&](const std::string& text) {
    write_text(dir.path() / "X.json", text);
    return message_of([&] {
      (void)files::bridge_model_set(files::load_instrument_model_set(dir.path(), "X"), all_fed);
    });
  };
  const std::string head = R"({"format": "endohaptics model set", "format_version": 1, )";
  const std::string src = "model set " + (dir.path() / "X.json").string() + ": ";
  CHECK(error_of(head + R"("instrument": "X", "models": {}, "colour": 1})") ==
        src + "unknown key 'colour' (allowed: format, format_version, instrument, models)");
  CHECK(error_of(head + R"("instrument": "X", "models": {"yaw": "a.json"}})")
            .starts_with(src + "unknown key 'models.yaw'"));
  CHECK(error_of(head + R"("instrument": "X", "models": {"clamp1": 3}})")
            .starts_with(src + "models.clamp1: must be a model file"));
  CHECK(error_of(R"({"format": "endohaptics model set", "format_version": 2, "instrument": "X",
                     "models": {}})")
            .starts_with(src + "format_version: must be 1"));
  CHECK(error_of(head + R"("models": {}})") == src + "missing field \"instrument\"");
  CHECK(error_of(head + R"("instrument": "Y", "models": {}})")
            .starts_with((dir.path() / "X.json").string().insert(0, "model set ") +
                         ": instrument: is 'Y'"));
  CHECK(error_of("{ not json").starts_with(src));
  // A missing model file and a bad preset: the set, the motor, the file.
  const std::string no_file =
      error_of(head + R"("instrument": "X", "models": {"clamp1": "gone.json", "clamp2":
               "preset:yaw2016", "roll": "preset:roll2016", "pitch": "preset:pitch2016"}})");
  CHECK(no_file.starts_with(src + "models.clamp1: "));
  CHECK(no_file.find("gone.json") != std::string::npos);
  CHECK(error_of(head + R"("instrument": "X", "models": {"clamp1": "preset:yaw2016", "clamp2":
               "preset:yaw2016", "roll": "preset:yaw2016", "pitch": "preset:pitch2016"}})")
            .starts_with(src + "models.roll: unknown preset 'preset:yaw2016'"));
  CHECK(error_of(head + R"("instrument": "X", "models": {"clamp1": "preset:yaw2016", "clamp2":
               "preset:yaw2016", "roll": "r.json", "pitch": "preset:pitch2016"}})")
            .find("models.roll: ") != std::string::npos);
  // The instrument's name is a plain file name; a set must exist.
  CHECK(message_of([&] {
          (void)files::load_instrument_model_set(dir.path(), "../X");
        }).find("an instrument name is letters") != std::string::npos);
  CHECK(message_of([&] {
          (void)files::load_instrument_model_set(dir.path(), "Z");
        }).find("no model set") != std::string::npos);
  // A set both as a file and as a folder: refused, both named; a folder holding no model.
  std::filesystem::create_directory(dir.path() / "X");
  CHECK(message_of([&] {
          (void)files::load_instrument_model_set(dir.path(), "X");
        }).find("/ exist: keep one") != std::string::npos);
  std::filesystem::remove(dir.path() / "X.json");
  CHECK(message_of([&] {
          (void)files::load_instrument_model_set(dir.path(), "X");
        }).find("holds no model_set.json and no clamp1.json") != std::string::npos);
}

TEST_CASE("model set: the bridge configuration chooses it by instrument, not with clamp_model") {
  const TempDir dir("model_set");
  std::filesystem::create_directories(dir.path() / "sets" / "EW3");
  save_stall_hold(dir.path() / "sets" / "EW3" / "clamp1.json");
  save_yaw(dir.path() / "sets" / "EW3" / "clamp2.json");
  write_text(dir.path() / "bridge.json",
             R"({"mapping": {"force_scale": [1, 0, 0]},
                 "estimator": {"model_sets": "sets", "instrument": "EW3"}})");
  const files::BridgeConfig config = files::load_bridge_config(dir.path() / "bridge.json");
  CHECK(config.model_sets == dir.path() / "sets");
  CHECK(config.instrument == "EW3");
  const files::BridgeModelSet b = files::bridge_config_force_models(config);
  CHECK(b.models.clamp1.get<est::StallHold<double>>() != nullptr);
  CHECK(b.description.starts_with("instrument EW3 ("));
  // Written and read back.
  CHECK(files::parse_bridge_config(files::bridge_config_json(config), "again").instrument == "EW3");
  // Roll fed back, not in the set: refused naming the key and the motor.
  write_text(dir.path() / "bridge.json",
             R"({"estimator": {"model_sets": "sets", "instrument": "EW3"}})");
  const std::string roll =
      message_of([&] { (void)files::load_bridge_config(dir.path() / "bridge.json"); });
  CHECK(roll.find("estimator.instrument: ") != std::string::npos);
  CHECK(roll.find("no model for roll, pitch") != std::string::npos);
  // Both a set and a clamp model: refused.
  write_text(dir.path() / "bridge.json",
             R"({"mapping": {"force_scale": [1, 0, 0]}, "estimator": {"model_sets": "sets",
                 "instrument": "EW3", "clamp_model": "preset:yaw2016"}})");
  CHECK(message_of([&] {
          (void)files::load_bridge_config(dir.path() / "bridge.json");
        }).find("not both") != std::string::npos);
  // An instrument without a folder of sets: refused.
  CHECK(message_of([&] {
          (void)files::parse_bridge_config(R"({"estimator": {"instrument": "EW3"}})", "b.json");
        }).find("no estimator.model_sets") != std::string::npos);
  CHECK(message_of([&] {
          (void)files::parse_bridge_config(R"({"estimator": {"instrument": ""}})", "b.json");
        }).starts_with("b.json: estimator.instrument: must be the instrument's name"));
}

}  // namespace files_model_set_test
