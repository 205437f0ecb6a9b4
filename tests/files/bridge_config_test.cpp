#include "endohaptics/files/bridge_config.hpp"

#include <doctest/doctest.h>

#include <filesystem>
#include <fstream>
#include <string>
#include <system_error>
#include <type_traits>

#include "endohaptics/files/model_file.hpp"
#include "endohaptics/model/presets_2016.hpp"
#include "test_support.hpp"

namespace files_bridge_config_test {

using endohaptics::test::message_of;
using endohaptics::test::TempDir;
using endohaptics::test::write_text;

namespace {

namespace files = endohaptics::files;
namespace tp = endohaptics::teleop;
using endohaptics::Error;

// The message parse_bridge_config gives for `text` (source "bridge.json").
std::string error_of(const std::string& text) {
  return message_of([&] { (void)files::parse_bridge_config(text, "bridge.json"); });
}

// The docs/rig.md example file.
const std::string rig_example = R"({
  "mapping":   { "a_roll": 0.7096, "b_roll": -1.108, "a_pitch": 3.93, "b_pitch": -0.54,
                 "a_clamp": 5.384, "b_clamp": 0.7,
                 "lower": [-1.028, -1.028, -1.028, -1.028], "upper": [1.028, 1.028, 1.028, 1.028],
                 "force_scale": [1, 1, 1], "force_limit": 2.5 },
  "safety":    { "max_consecutive_misses": 10, "policy": "disable_motors", "max_hold_time": 2.0,
                 "force_ramp_time": 0.5, "max_setpoint_rate": 4.0, "max_stylus_force": 3.0,
                 "enable_mask": 15 },
  "estimator": { "current_sign": [-1, -1, -1, -1], "friction_level": [0.7, 0.17, 0.21, 0.20],
                 "output_deadzone": [0, 0, 0, 0], "output_limit": [0.084, 9.80665, 9.80665, 9.80665] },
  "operator":  { "r_open": 0.1300, "r_closed": 0.0186, "open_time": 0.7, "close_time": 0.8,
                 "hold_time": 0.7, "release_time": 0.8 },
  "loop":      { "receive_timeout": 0.001 }
})";

// Nested arrays `depth` deep as the value of mapping.lower.
std::string nested(int depth) {
  return R"({"mapping": {"lower": )" + std::string(static_cast<std::size_t>(depth) - 2, '[') +
         std::string(static_cast<std::size_t>(depth) - 2, ']') + "}}";
}

}  // namespace

TEST_CASE("defaults: an empty object, and the defaults written and read back, give the library's") {
  const files::BridgeConfig defaults;
  const files::BridgeConfig empty = files::parse_bridge_config("{}");
  CHECK(files::bridge_config_json(empty) == files::bridge_config_json(defaults));

  const std::string text = files::bridge_config_json(defaults);
  const files::BridgeConfig back = files::parse_bridge_config(text);
  CHECK(files::bridge_config_json(back) == text);
  CHECK(back.mapping.a_roll == defaults.mapping.a_roll);
  CHECK(back.mapping.lower == defaults.mapping.lower);
  CHECK(back.mapping.theta_neutral == defaults.mapping.theta_neutral);
  CHECK(back.loop.safety.max_consecutive_misses == 10);
  CHECK(back.loop.safety.policy == tp::SafeStatePolicy::disable_motors);
  CHECK(back.loop.safety.max_hold_time == 2.0);
  CHECK(back.loop.safety.enable_mask == 0x0F);
  CHECK(back.loop.receive_timeout == defaults.loop.receive_timeout);
  CHECK(back.estimator.friction == defaults.estimator.friction);
  CHECK(back.estimator.output_limit == defaults.estimator.output_limit);
  CHECK(back.operator_script.r_closed == defaults.operator_script.r_closed);
  CHECK(back.clamp_model.empty());
  // Every section and key is written.
  for (const char* key :
       {"\"mapping\"", "\"safety\"", "\"estimator\"", "\"operator\"", "\"loop\"",
        "\"max_consecutive_misses\"", "\"friction_level\"", "\"receive_timeout\"",
        "\"theta_neutral\"", "\"disable_motors\"", "\"max_hold_time\"", "\"activation_timeout\""}) {
    CHECK(text.find(key) != std::string::npos);
  }
}

TEST_CASE("a changed value of every kind round-trips through the JSON text") {
  files::BridgeConfig c;
  c.mapping.b_clamp = 0.25;
  c.mapping.upper << 1.0, 0.9, 0.8, 0.7;
  c.loop.safety.policy = tp::SafeStatePolicy::zero_force;
  c.loop.safety.max_consecutive_misses = 3;
  c.loop.safety.enable_mask = 0x05;
  c.loop.receive_timeout = std::chrono::microseconds(250);
  c.estimator.current_sign << 1, -1, 1, -1;
  c.estimator.friction[1] = endohaptics::model::JointFriction<double>::simplified(0.3);
  c.operator_script.hold_time = 0.0;
  const files::BridgeConfig back = files::parse_bridge_config(files::bridge_config_json(c));
  CHECK(back.mapping.b_clamp == 0.25);
  CHECK(back.mapping.upper == c.mapping.upper);
  CHECK(back.loop.safety.policy == tp::SafeStatePolicy::zero_force);
  CHECK(back.loop.safety.max_consecutive_misses == 3);
  CHECK(back.loop.safety.enable_mask == 0x05);
  CHECK(back.loop.receive_timeout == std::chrono::microseconds(250));
  CHECK(back.estimator.current_sign == c.estimator.current_sign);
  CHECK(back.estimator.friction[1].static_level == 0.3);
  CHECK(back.estimator.friction[1].coulomb_level == 0.3);
  CHECK(back.operator_script.hold_time == 0.0);
}

TEST_CASE("the docs/rig.md example loads from a file, comments allowed") {
  TempDir dir("rig_example");
  write_text(dir.path() / "bridge.json", "// the lab's settings\n" + rig_example);
  const files::BridgeConfig c = files::load_bridge_config(dir.path() / "bridge.json");
  CHECK(c.mapping.a_pitch == 3.93);
  CHECK(c.loop.safety.max_setpoint_rate == 4.0);
  CHECK(c.estimator.friction[3].static_level == 0.20);
  CHECK(c.loop.receive_timeout == std::chrono::milliseconds(1));

  const auto p = files::parse_bridge_config(
      R"({ /* block */ "safety": { "policy": "disable_motors" } // trailing
      })");
  CHECK(p.loop.safety.policy == tp::SafeStatePolicy::disable_motors);
}

TEST_CASE("file errors name the file") {
  TempDir dir("file_errors");
  const auto missing = dir.path() / "missing.json";
  CHECK(message_of([&] { (void)files::load_bridge_config(missing); }) ==
        "configuration file '" + missing.string() + "' cannot be opened: the file does not exist");

  const auto bad = dir.path() / "bad.json";
  write_text(bad, "{\n  \"safety\": { \"policy\": \"zero_force\", }\n}");
  const std::string m = message_of([&] { (void)files::load_bridge_config(bad); });
  CHECK(m.rfind(bad.string() + ": not valid JSON: parse error at line 2, column ", 0) == 0);

  const auto range = dir.path() / "range.json";
  write_text(range, R"({"loop": {"receive_timeout": 2}})");
  CHECK(message_of([&] { (void)files::load_bridge_config(range); }) ==
        range.string() + ": loop.receive_timeout: must be in (0, 0.5] s, got 2");
  // 0 would never wait for an answer: v2 never connected (before: accepted).
  write_text(range, R"({"loop": {"receive_timeout": 0}})");
  CHECK(message_of([&] { (void)files::load_bridge_config(range); }) ==
        range.string() + ": loop.receive_timeout: must be in (0, 0.5] s, got 0");
  // A mapping gain of 0 silently removed the clamp's force feedback (before: accepted).
  write_text(range, R"({"mapping": {"a_clamp": 0}})");
  CHECK(message_of([&] { (void)files::load_bridge_config(range); })
            .find("a_clamp: must be of magnitude in [1e-6, 1e6] (a gain of 0 freezes the joint and "
                  "removes its force feedback), got 0") != std::string::npos);

  const auto big = dir.path() / "big.json";
  write_text(big, "{}" + std::string(files::bridge_config_max_bytes, ' '));
  CHECK(message_of([&] { (void)files::load_bridge_config(big); }) ==
        "configuration file '" + big.string() +
            "' holds 1048578 bytes, more than the limit of 1048576 bytes "
            "(files::bridge_config_max_bytes; a complete one is under 2 kB)");
}

TEST_CASE("unknown keys are errors that list the allowed keys") {
  CHECK(error_of(R"({"safty": {}})") ==
        "bridge.json: unknown key 'safty' (allowed: mapping, safety, plausibility, estimator, "
        "operator, loop, passivity)");
  CHECK(error_of(R"({"loop": {"recieve_timeout": 0.002}})") ==
        "bridge.json: unknown key 'loop.recieve_timeout' (allowed in 'loop': receive_timeout)");
  CHECK(error_of(R"({"safety": {"polcy": "zero_force"}})") ==
        "bridge.json: unknown key 'safety.polcy' (allowed in 'safety': max_consecutive_misses, "
        "policy, max_hold_time, force_ramp_time, max_setpoint_rate, max_stylus_force, enable_mask, "
        "activation_timeout, joint_lower, joint_upper)");
  // loop_period and motor_order are the program's, not the file's.
  CHECK(error_of(R"({"estimator": {"loop_period": 0.002}})")
            .rfind("bridge.json: unknown key 'estimator.loop_period' (allowed in 'estimator': "
                   "current_sign, unit_scale, friction_level, output_deadzone, output_limit, "
                   "stick_travel, stick_play, stick_force, clamp_model, model_sets, instrument)",
                   0) == 0);
}

TEST_CASE("the passivity section sets the layer --passivity tdpa runs") {
  // docs/rig.md: the passivity sweep's stable setting for the sensorless estimate.
  const auto c = files::parse_bridge_config(
      R"({ "passivity": { "observer": "per_direction", "gain_recovery_rate": 0.05,
                          "robot_cost_tolerance": [0, 0, 0.014, 0.014] } })",
      "bridge.json");
  CHECK(c.loop.passivity.observer == tp::PassivityObserver::per_direction);
  CHECK(c.loop.passivity.gain_recovery_rate == 0.05);
  CHECK(c.loop.passivity.robot_cost_tolerance[2] == 0.014);
  CHECK(c.loop.passivity.robot_cost_tolerance[0] == 0.0);
  CHECK(c.loop.passivity.energy_reserve == tp::PassivityConfig{}.energy_reserve);
  // The mode, the round trip and the force limit are the program's (--passivity, the mapping).
  CHECK(c.loop.passivity.mode == tp::PassivityMode::off);
  CHECK(error_of(R"({"passivity": {"mode": "tdpa"}})")
            .starts_with("bridge.json: unknown key 'passivity.mode' (allowed in 'passivity': "
                         "observer, energy_reserve, gain_recovery_rate, estimate_tolerance, "
                         "robot_cost_tolerance, robot_return_needs_motion, "
                         "recover_while_absorbing, lever, min_motion)"));
  // Written and read back, booleans as booleans.
  auto flags = c;
  flags.loop.passivity.recover_while_absorbing = true;
  flags.loop.passivity.robot_return_needs_motion = false;
  const std::string text = files::bridge_config_json(flags);
  CHECK(text.find(R"("recover_while_absorbing": true)") != std::string::npos);
  const auto back = files::parse_bridge_config(text);
  CHECK(back.loop.passivity.recover_while_absorbing);
  CHECK_FALSE(back.loop.passivity.robot_return_needs_motion);
  CHECK(back.loop.passivity.observer == tp::PassivityObserver::per_direction);
  CHECK(files::bridge_config_json(back) == text);
  // Refused with the key, the rule and the value.
  CHECK(error_of(R"({"passivity": {"observer": "both"}})") ==
        R"(bridge.json: passivity.observer: must be "combined" or "per_direction", got "both")");
  CHECK(error_of(R"({"passivity": {"recover_while_absorbing": 1}})") ==
        "bridge.json: passivity.recover_while_absorbing: must be true or false, got 1");
  CHECK(error_of(R"({"passivity": {"robot_cost_tolerance": [0, 0, -0.1, 0]}})") ==
        "bridge.json: passivity.robot_cost_tolerance[2]: must be in [0, 10] N, got -0.1");
  CHECK(error_of(R"({"passivity": {"estimate_tolerance": [0, 0, 1e300, 0]}})") ==
        "bridge.json: passivity.estimate_tolerance[2]: must be in [0, 10] N, got 1e+300");
  CHECK(error_of(R"({"passivity": {"energy_reserve": 0}})") ==
        "bridge.json: passivity.energy_reserve: must be finite and > 0 J, got 0");
  // A built configuration is checked the same way (the section named by the library's error).
  files::BridgeConfig bad;
  bad.loop.passivity.gain_recovery_rate = -1.0;
  CHECK(message_of([&] { files::validate_bridge_config(bad, "built"); }) ==
        "built: passivity.gain_recovery_rate: must be finite and > 0 1/s, got -1");
}

TEST_CASE("duplicate keys are errors, at any level") {
  CHECK(error_of(R"({"safety": {"policy": "zero_force", "policy": "hold_position"}})") ==
        "bridge.json: line 1, column 44: duplicate key 'safety.policy' (a key may appear only "
        "once)");
  CHECK(error_of(R"({"loop": {}, "mapping": {}, "loop": {"receive_timeout": 0.002}})") ==
        "bridge.json: line 1, column 34: duplicate key 'loop' (a key may appear only once)");
  // The same key in two different objects is fine.
  CHECK_NOTHROW((void)files::parse_bridge_config(
      R"({"mapping": {"force_limit": 2}, "safety": {"max_stylus_force": 2}})"));
}

TEST_CASE("wrong types name the key and what it must be") {
  CHECK(error_of("[1, 2]") == "bridge.json: must be a JSON object {...}, got [1,2]");
  CHECK(error_of(R"({"safety": 3})") == "bridge.json: safety: must be an object {...}, got 3");
  CHECK(error_of(R"({"mapping": {"a_roll": "0.7"}})") ==
        "bridge.json: mapping.a_roll: must be a number (of magnitude in [1e-6, 1e6] (a gain of 0 "
        "freezes the joint and removes its force feedback)), got \"0.7\"");
  CHECK(error_of(R"({"mapping": {"lower": [0, 0, 0]}})") ==
        "bridge.json: mapping.lower: must be an array of 4 numbers, each finite rad, got "
        "[0,0,0]");
  // Within the EndoWrist's joint limit, as the safety ranges are.
  CHECK(error_of(R"({"mapping": {"upper": [1, 1, 1, 4]}})") ==
        "bridge.json: mapping.upper[3]: must be in [-pi, pi] rad, got 4");
  CHECK(error_of(R"({"mapping": {"force_scale": [1, null, 1]}})") ==
        "bridge.json: mapping.force_scale[1]: must be a number (in [0, 100] N per unit), got null");
  CHECK(error_of(R"({"safety": {"policy": "freeze"}})") ==
        "bridge.json: safety.policy: must be \"hold_position\", \"disable_motors\" or "
        "\"zero_force\", got \"freeze\"");
  CHECK(error_of(R"({"safety": {"policy": 1}})") ==
        "bridge.json: safety.policy: must be \"hold_position\", \"disable_motors\" or "
        "\"zero_force\", got 1");
}

TEST_CASE("integer fields: integral and in range, never an undefined conversion") {
  const std::string misses =
      "bridge.json: safety.max_consecutive_misses: must be an integer in "
      "[0, 1000], got ";
  auto misses_of = [](const std::string& value) {
    return error_of(R"({"safety": {"max_consecutive_misses": )" + value + "}}");
  };
  CHECK(misses_of("1e300") == misses + "1e+300");
  CHECK(misses_of("-1e300") == misses + "-1e+300");
  CHECK(misses_of("10.5") == misses + "10.5");
  CHECK(misses_of("-1") == misses + "-1");
  CHECK(misses_of("1000001") == misses + "1000001");
  CHECK(misses_of("18446744073709551615") == misses + "18446744073709551615");
  CHECK(misses_of("-9223372036854775808") == misses + "-9223372036854775808");
  CHECK(misses_of("1e400") == "bridge.json: not valid JSON: number overflow parsing '1e400'");
  CHECK(misses_of("\"10\"") == misses + "\"10\"");
  CHECK(misses_of("true") == misses + "true");
  // An integral float is an integer.
  CHECK(files::parse_bridge_config(R"({"safety": {"max_consecutive_misses": 2e1}})")
            .loop.safety.max_consecutive_misses == 20);
  CHECK(files::parse_bridge_config(R"({"safety": {"max_consecutive_misses": 0}})")
            .loop.safety.max_consecutive_misses == 0);

  // A byte, then only the 4 motors' bits (SafetyConfig::validate's rule).
  const std::string mask = "bridge.json: safety.enable_mask: must be an integer in [0, 255], got ";
  CHECK(error_of(R"({"safety": {"enable_mask": 16}})") ==
        "bridge.json: safety.enable_mask: must be <= 0x0F (bits 0..3: 4 motors), got 0x10");
  CHECK(error_of(R"({"safety": {"enable_mask": 256}})") == mask + "256");  // not 0 as a uint8
  CHECK(error_of(R"({"safety": {"enable_mask": 1.5}})") == mask + "1.5");
  CHECK(files::parse_bridge_config(R"({"safety": {"enable_mask": 3}})").loop.safety.enable_mask ==
        3);
}

TEST_CASE("out-of-range numbers name the key and the allowed range") {
  CHECK(error_of(R"({"mapping": {"force_limit": 0}})") ==
        "bridge.json: mapping.force_limit: must be finite and > 0 N, got 0");
  CHECK(error_of(R"({"mapping": {"min_radius": -0.001}})") ==
        "bridge.json: mapping.min_radius: must be finite and >= 0 m, got -0.001");
  CHECK(error_of(R"({"mapping": {"theta_neutral": 4}})") ==
        "bridge.json: mapping.theta_neutral: must be in [-pi, pi] rad, got 4");
  CHECK(error_of(R"({"mapping": {"a_roll": 1e999}})") ==
        "bridge.json: not valid JSON: number overflow parsing '1e999'");
  CHECK(error_of(R"({"safety": {"max_setpoint_rate": 0}})") ==
        "bridge.json: safety.max_setpoint_rate: must be in (0, 40] rad/s, got 0");
  CHECK(error_of(R"({"safety": {"force_ramp_time": -0.5}})") ==
        "bridge.json: safety.force_ramp_time: must be in [0, 10] s, got -0.5");
  CHECK(error_of(R"({"estimator": {"current_sign": [-1, -1, 0.5, -1]}})") ==
        "bridge.json: estimator.current_sign[2]: must be +1 or -1, got 0.5");
  CHECK(error_of(R"({"estimator": {"friction_level": [0.7, -0.17, 0.21, 0.2]}})") ==
        "bridge.json: estimator.friction_level[1]: must be finite and >= 0 A, got -0.17");
  CHECK(error_of(R"({"estimator": {"output_limit": [0.084, 9.8, 0, 9.8]}})") ==
        "bridge.json: estimator.output_limit[2]: must be finite and > 0, got 0");
  CHECK(error_of(R"({"operator": {"close_time": 0}})") ==
        "bridge.json: operator.close_time: must be finite and > 0 s, got 0");
  CHECK(error_of(R"({"loop": {"receive_timeout": -0.001}})") ==
        "bridge.json: loop.receive_timeout: must be in (0, 0.5] s, got -0.001");
}

TEST_CASE("cross-field checks of the library come with the file name") {
  CHECK(error_of(R"({"mapping": {"lower": [1, -1, -1, -1], "upper": [0, 1, 1, 1]}})") ==
        "bridge.json: mapping: CylindricalMapper: range of roll is empty: lower 1 > upper 0");
  // A clamp model whose sample time the 1 ms Decimate grid cannot run is refused at load.
  files::BridgeConfig c;
  c.estimator.loop_period = 0.003;  // not a divisor of the 2016 models' 0.02 s
  CHECK(message_of([&] {
          files::validate_bridge_config(c, "built");
        }).rfind("built: estimator: ForceEstimator", 0) == 0);
}

TEST_CASE("validate_bridge_config checks a configuration built in code") {
  files::BridgeConfig c;
  CHECK_NOTHROW(files::validate_bridge_config(c));
  c.loop.safety.enable_mask = 0x10;
  CHECK(message_of([&] { files::validate_bridge_config(c, "built"); }) ==
        "built: safety.enable_mask: must be <= 0x0F (bits 0..3: 4 motors), got 0x10");
  c = {};
  c.loop.receive_timeout = std::chrono::seconds(2);
  CHECK(message_of([&] { files::validate_bridge_config(c, "built"); }) ==
        "built: loop.receive_timeout: must be in (0, 0.5] s, got 2");
  c = {};
  c.operator_script.r_open = std::numeric_limits<double>::quiet_NaN();
  CHECK(message_of([&] { files::validate_bridge_config(c, "built"); }) ==
        "built: operator.r_open: must be finite and > 0 m, got nan");
}

TEST_CASE("echoed values and keys are cut to 60 characters") {
  const std::string long_text(100000, 'x');
  const std::string value = error_of(R"({"safety": {"policy": ")" + long_text + "\"}}");
  CHECK(value ==
        "bridge.json: safety.policy: must be \"hold_position\", \"disable_motors\" or "
        "\"zero_force\", got \"" +
            std::string(59, 'x') + "...");
  const std::string key = error_of(R"({"safety": {")" + long_text + "\": 1}}");
  CHECK(key ==
        "bridge.json: unknown key 'safety." + std::string(53, 'x') +
            "...' (allowed in 'safety': max_consecutive_misses, policy, max_hold_time, "
            "force_ramp_time, "
            "max_setpoint_rate, max_stylus_force, enable_mask, activation_timeout, joint_lower, "
            "joint_upper)");
  const std::string array =
      error_of(R"({"mapping": {"lower": [)" + std::string(50000, '1') + ", 2, 3]}}");
  CHECK(array ==
        "bridge.json: not valid JSON: number overflow parsing '" + std::string(60, '1') + "...'");
  // An invalid token: nlohmann echoes it; the message keeps 60 characters of it.
  const std::string token = error_of(R"({"safety": {"policy": ")" + long_text);
  CHECK(token.rfind("bridge.json: not valid JSON: parse error at line 1, column ", 0) == 0);
  CHECK(token.size() < 300);
  CHECK(token.find(std::string(59, 'x') + "...") != std::string::npos);
  const std::string literal = error_of(R"({"safety": {"policy": t)" + long_text + "}}");
  CHECK(literal.size() < 300);
}

TEST_CASE("nesting deeper than 64 levels is refused by the parser, before it descends further") {
  CHECK(error_of(nested(65)) ==
        "bridge.json: line 1, column 85: nested deeper than 64 levels (the limit; the bridge "
        "configuration needs 3)");
  // 64 levels parse; the schema then refuses the value.
  CHECK(
      error_of(nested(64)).rfind("bridge.json: mapping.lower: must be an array of 4 numbers", 0) ==
      0);
  // A depth that would exhaust a recursive parser's stack, and one that is unterminated.
  const std::string deep(1000000, '[');
  CHECK(error_of(deep).find("nested deeper than 64 levels") != std::string::npos);
  CHECK(error_of("{\"a\":\n" + std::string(70, '[')).rfind("bridge.json: line 2, column 64: ", 0) ==
        0);
  // Objects nest as arrays do; an object that opens where a key belongs is invalid JSON, refused
  // as such (the bracket counter that ran before the parser called it too deep).
  CHECK(error_of("{\"a\":\n" + std::string(70, '{'))
            .rfind("bridge.json: not valid JSON: parse error at line 2, column 2", 0) == 0);
  // Brackets inside strings and comments do not count.
  const std::string brackets(100, '[');
  CHECK(error_of("{\"" + brackets + "\": 1}").rfind("bridge.json: unknown key '[[[", 0) == 0);
  CHECK_NOTHROW((void)files::parse_bridge_config("// " + brackets + "\n/* " + brackets + " */{}"));
  CHECK(error_of(R"({"estimator": {"clamp_model": ")" + brackets + R"("}})")
            .rfind("bridge.json: estimator.clamp_model: ", 0) == 0);
}

TEST_CASE("estimator.clamp_model loads an identified model file, relative to the config file") {
  TempDir dir("clamp_model");
  // The appendix C yaw model with a 0.3 A dead zone, as endohaptics-identify would save it.
  const auto yaw = endohaptics::model::yaw_force_2016_hw(0.3);
  files::save_model(
      dir.path() / "clamp.json",
      files::make_model_file(yaw, {{"current", "A"}, {"velocity", "rad/s"}}, {{"force", "N"}}));
  write_text(dir.path() / "bridge.json", R"({"estimator": {"clamp_model": "clamp.json"}})");
  const files::BridgeConfig c = files::load_bridge_config(dir.path() / "bridge.json");
  CHECK(c.clamp_model == dir.path() / "clamp.json");
  const auto models =
      endohaptics::estimation::bridge_force_models(files::load_bridge_joint_model(c.clamp_model));
  REQUIRE(models.clamp1.get<endohaptics::estimation::IdentifiedHammersteinWiener<double>>() !=
          nullptr);
  REQUIRE(models.clamp2.get<endohaptics::estimation::IdentifiedHammersteinWiener<double>>() !=
          nullptr);
  CHECK(models.clamp1.get<endohaptics::estimation::IdentifiedHammersteinWiener<double>>()
            ->model()
            .input_nonlinearity()
            .channel(0)
            .upper() == 0.3);
  CHECK(models.clamp2.get<endohaptics::estimation::IdentifiedHammersteinWiener<double>>()
            ->model()
            .input_nonlinearity()
            .channel(0)
            .upper() == 0.3);
  CHECK(endohaptics::estimation::bridge_force_models()
            .clamp1.get<endohaptics::estimation::ClampModel2016<double>>()
            ->model()
            .input_nonlinearity()
            .channel(0)
            .upper() == doctest::Approx(0.21));

  // An absolute path stays as it is; the key round-trips.
  const auto absolute = files::parse_bridge_config(R"({"estimator": {"clamp_model": ")" +
                                                   (dir.path() / "clamp.json").string() + "\"}}");
  CHECK(absolute.clamp_model == dir.path() / "clamp.json");
  CHECK(files::parse_bridge_config(files::bridge_config_json(absolute)).clamp_model ==
        absolute.clamp_model);

  // A missing or unusable model file is an error of the configuration file, naming both.
  write_text(dir.path() / "missing.json", R"({"estimator": {"clamp_model": "nope.json"}})");
  const std::string missing =
      message_of([&] { (void)files::load_bridge_config(dir.path() / "missing.json"); });
  CHECK(missing.rfind((dir.path() / "missing.json").string() + ": estimator.clamp_model: ", 0) ==
        0);
  CHECK(missing.find((dir.path() / "nope.json").string()) != std::string::npos);
  CHECK(error_of(R"({"estimator": {"clamp_model": 3}})") ==
        "bridge.json: estimator.clamp_model: must be the name of a model file (a non-empty "
        "string), got 3");
  CHECK(error_of(R"({"estimator": {"clamp_model": ""}})") ==
        "bridge.json: estimator.clamp_model: must be the name of a model file (a non-empty "
        "string), got \"\"");
}

TEST_CASE("estimator.clamp_model of a lower order runs in the bridge's 6 states, unchanged") {
  TempDir dir("clamp_model_order");
  // An order-2 Hammerstein-Wiener clamp model (what endohaptics-identify --order 2 writes).
  const Eigen::Matrix2d A{{0.95, 0.02}, {-0.01, 0.9}};
  const Eigen::Matrix<double, 2, 2> B{{0.4, 0.01}, {0.1, -0.02}};
  const Eigen::Matrix<double, 1, 2> C{{0.8, 0.3}};
  const Eigen::Matrix<double, 1, 2> D{{0.05, 0.0}};
  const endohaptics::model::StateSpace<2, 2, 1> low(A, B, C, D, 0.001);
  files::ModelFile file =
      files::make_model_file(low, {{"current", "A"}, {"velocity", "rad/s"}}, {{"force", "N"}});
  file.input_nonlinearity = {{endohaptics::model::StaticMapKind::deadzone, -0.19, 0.19}, {}};
  file.output_nonlinearity = {{}};
  files::save_model(dir.path() / "clamp.json", file);
  write_text(dir.path() / "bridge.json", R"({"estimator": {"clamp_model": "clamp.json"}})");
  const auto models = endohaptics::estimation::bridge_force_models(files::load_bridge_joint_model(
      files::load_bridge_config(dir.path() / "bridge.json").clamp_model));
  REQUIRE(models.clamp1.get<endohaptics::estimation::IdentifiedHammersteinWiener<double>>() !=
          nullptr);
  const auto& linear =
      models.clamp1.get<endohaptics::estimation::IdentifiedHammersteinWiener<double>>()
          ->model()
          .linear();
  static_assert(std::remove_cvref_t<decltype(linear)>::states ==
                endohaptics::estimation::bridge_clamp_states);
  CHECK(linear.A().topLeftCorner<2, 2>() == A);
  CHECK(linear.A().rightCols<4>().isZero());
  CHECK(linear.A().bottomRows<4>().isZero());
  CHECK(linear.dc_gain() == low.dc_gain());
  CHECK(models.clamp1.get<endohaptics::estimation::IdentifiedHammersteinWiener<double>>()
            ->model()
            .input_nonlinearity()
            .channel(0)
            .upper() == 0.19);
  // Seven states do not fit: refused, naming the file.
  const endohaptics::model::StateSpace<7, 2, 1> seven(
      Eigen::Matrix<double, 7, 7>::Identity() * 0.5, Eigen::Matrix<double, 7, 2>::Ones(),
      Eigen::Matrix<double, 1, 7>::Ones(), Eigen::Matrix<double, 1, 2>::Zero(), 0.001);
  files::save_model(
      dir.path() / "seven.json",
      files::make_model_file(seven, {{"current", "A"}, {"velocity", "rad/s"}}, {{"force", "N"}}));
  write_text(dir.path() / "bridge7.json", R"({"estimator": {"clamp_model": "seven.json"}})");
  const std::string too_big =
      message_of([&] { (void)files::load_bridge_config(dir.path() / "bridge7.json"); });
  CHECK(too_big.find("seven.json") != std::string::npos);
  CHECK(too_big.find("7 states") != std::string::npos);
  // An unstable linear block is refused (before: it loaded and its estimate diverged to Inf).
  const endohaptics::model::StateSpace<2, 2, 1> unstable(Eigen::Matrix2d{{1.01, 0.0}, {0.0, 0.5}},
                                                         B, C, D, 0.001);
  files::save_model(dir.path() / "unstable.json",
                    files::make_model_file(unstable, {{"current", "A"}, {"velocity", "rad/s"}},
                                           {{"force", "N"}}));
  write_text(dir.path() / "bridge_unstable.json",
             R"({"estimator": {"clamp_model": "unstable.json"}})");
  const std::string unstable_error =
      message_of([&] { (void)files::load_bridge_config(dir.path() / "bridge_unstable.json"); });
  CHECK(unstable_error.find("unstable.json: the clamp model is not stable (spectral radius 1.01, "
                            "must be < 1)") != std::string::npos);
  // A number far beyond any force model (C = 1e308) is refused (before: accepted, the estimate
  // pinned at its limit on every tick).
  const endohaptics::model::StateSpace<2, 2, 1> huge(Eigen::Matrix2d{{0.9, 0.0}, {0.0, 0.5}}, B,
                                                     Eigen::Matrix<double, 1, 2>{{1e308, 0.0}}, D,
                                                     0.001);
  files::save_model(
      dir.path() / "huge.json",
      files::make_model_file(huge, {{"current", "A"}, {"velocity", "rad/s"}}, {{"force", "N"}}));
  write_text(dir.path() / "bridge_huge.json", R"({"estimator": {"clamp_model": "huge.json"}})");
  const std::string huge_error =
      message_of([&] { (void)files::load_bridge_config(dir.path() / "bridge_huge.json"); });
  CHECK(huge_error.find("huge.json: C[0][0] is 1e+308: a clamp force model's numbers must lie in "
                        "[-1e6, 1e6]") != std::string::npos);
}

TEST_CASE("safety-relevant values have physical bounds (docs/safety.md, configuration bounds)") {
  // Before: each of these was accepted and switched a safety function off.
  CHECK(error_of(R"({"safety": {"max_consecutive_misses": 2147483647}})") ==
        "bridge.json: safety.max_consecutive_misses: must be an integer in [0, 1000], got "
        "2147483647");
  CHECK(error_of(R"({"safety": {"max_stylus_force": 1e308}})") ==
        "bridge.json: safety.max_stylus_force: must be in [0, 3.3] N (the Touch's peak), got "
        "1e+308");
  CHECK(error_of(R"({"mapping": {"force_limit": 1e308}})") ==
        "bridge.json: mapping.force_limit: must be in (0, 3.3] N, got 1e+308");
  CHECK(error_of(R"({"mapping": {"force_scale": [1, -1, 1]}})") ==
        "bridge.json: mapping.force_scale[1]: must be in [0, 100] N per unit, got -1");
  CHECK(error_of(R"({"safety": {"force_ramp_time": -0.9}})") ==
        "bridge.json: safety.force_ramp_time: must be in [0, 10] s, got -0.9");
  // 300 misses at the default 1 ms are 0.3 s: accepted; 1000 are 1 s: refused by the loop.
  CHECK(files::parse_bridge_config(R"({"safety": {"max_consecutive_misses": 300}})")
            .loop.safety.max_consecutive_misses == 300);
  CHECK(error_of(R"({"safety": {"max_consecutive_misses": 1000}})")
            .starts_with("bridge.json: safety: TeleopLoopConfig: (safety.max_consecutive_misses "
                         "+ 1) x max(period, receive_timeout) = 1001 x 1000000 ns"));
}

TEST_CASE("the joint range and the plausibility bounds are keys, checked and round-tripped") {
  const auto c = files::parse_bridge_config(R"({
    "safety": {"joint_lower": [-1, -0.5, -1, -1], "joint_upper": [1, 0.5, 1, 1]},
    "plausibility": {"position_margin": 0.1, "max_velocity": 20, "max_current": 5,
                     "jump_tolerance": 0.02}})");
  CHECK(c.loop.safety.joint_lower[1] == -0.5);
  CHECK(c.loop.safety.joint_upper[1] == 0.5);
  CHECK(c.loop.safety.plausibility.position_margin == 0.1);
  CHECK(c.loop.safety.plausibility.max_velocity == 20.0);
  CHECK(c.loop.safety.plausibility.max_current == 5.0);
  CHECK(c.loop.safety.plausibility.jump_tolerance == 0.02);
  const auto back = files::parse_bridge_config(files::bridge_config_json(c));
  CHECK(back.loop.safety.joint_upper == c.loop.safety.joint_upper);
  CHECK(back.loop.safety.plausibility.max_current == 5.0);

  CHECK(files::parse_bridge_config(R"({"mapping": {"channel_limit": [2, 0.5, 0.5]}})")
            .mapping.channel_limit[1] == 0.5);
  CHECK(error_of(R"({"mapping": {"channel_limit": [1, 1, 10]}})") ==
        "bridge.json: mapping.channel_limit[2]: must be in (0, 3.3] N, got 10");
  CHECK(error_of(R"({"plausibility": {"max_current": 100}})") ==
        "bridge.json: plausibility.max_current: must be in (0, 15] A, got 100");
  CHECK(error_of(R"({"plausibility": {"max_velocity": 0}})") ==
        "bridge.json: plausibility.max_velocity: must be in (0, 40] rad/s, got 0");
  CHECK(error_of(R"({"safety": {"joint_upper": [1, 1, 1, 4]}})") ==
        "bridge.json: safety.joint_upper[3]: must be in [-pi, pi] rad, got 4");
  CHECK(error_of(R"({"safety": {"joint_lower": [0, 0, 0, 2]}})") ==
        "bridge.json: safety.joint_upper[3]: must be above joint_lower[3], got 1.028");
}

}  // namespace files_bridge_config_test
