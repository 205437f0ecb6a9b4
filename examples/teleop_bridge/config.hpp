// The bridge's --config file (JSON): every field optional, defaults are the library's (the
// 2016 rig). Unknown keys are errors, so a typo never silently keeps a default.
// docs/rig.md shows a complete file.
#pragma once

#include <endohaptics/core/error.hpp>
#include <endohaptics/estimation/force_estimator.hpp>
#include <endohaptics/kinematics/cylindrical_mapper.hpp>
#include <endohaptics/sim/scripted_operator.hpp>
#include <endohaptics/teleop/teleop_loop.hpp>
#include <filesystem>
#include <fstream>
#include <map>
#include <nlohmann/json.hpp>
#include <set>
#include <string>

namespace bridge {

struct Config {
  endohaptics::kinematics::CylindricalMapperConfig<double> mapping{};
  endohaptics::teleop::SafetyConfig safety{};
  endohaptics::estimation::ForceEstimatorSettings<double> estimator{};
  endohaptics::sim::OperatorScript operator_script{};
  std::string clamp_model;  // model file (JSON) for both clamps; empty: the appendix C yaw model
  double receive_timeout = 1e-3;  // s
};

namespace detail {

using endohaptics::Error;
using nlohmann::json;

inline void only_keys(const json& j, const std::string& where, const std::set<std::string>& keys) {
  if (!j.is_object()) throw Error("config: '" + where + "' must be an object");
  for (const auto& [key, value] : j.items()) {
    if (!keys.contains(key)) throw Error("config: unknown key '" + where + "." + key + "'");
  }
}

inline double number(const json& j, const std::string& where) {
  if (!j.is_number()) throw Error("config: '" + where + "' must be a number, got " + j.dump());
  return j.get<double>();
}

template <typename Vector>
void vector(const json& j, const std::string& where, Vector& out) {
  if (!j.is_array() || j.size() != static_cast<std::size_t>(out.size())) {
    throw Error("config: '" + where + "' must be an array of " + std::to_string(out.size()) +
                " numbers, got " + j.dump());
  }
  for (Eigen::Index i = 0; i < out.size(); ++i) {
    out[i] = number(j[static_cast<std::size_t>(i)], where + "[" + std::to_string(i) + "]");
  }
}

inline void set(const json& j, const std::string& where, const char* key, double& out) {
  if (j.contains(key)) out = number(j.at(key), where + "." + key);
}

}  // namespace detail

//! Reads `path` over the defaults. Throws endohaptics::Error naming the file and the field.
inline Config load_config(const std::string& path) {
  using namespace detail;
  Config c;
  std::ifstream in(path);
  if (!in) throw Error("config: cannot read '" + path + "'");
  json j;
  try {
    j = json::parse(in, nullptr, true, /*ignore_comments=*/true);
  } catch (const json::parse_error& e) {
    throw Error("config: '" + path + "' is not valid JSON: " + e.what());
  }
  try {
    only_keys(j, "", {"mapping", "safety", "estimator", "operator", "loop"});
    if (j.contains("mapping")) {
      const json& m = j["mapping"];
      only_keys(m, "mapping",
                {"a_roll", "b_roll", "a_pitch", "b_pitch", "a_clamp", "b_clamp", "lower", "upper",
                 "min_radius", "theta_neutral", "force_scale", "force_limit"});
      auto& o = c.mapping;
      for (auto [key, field] : std::map<const char*, double*>{{"a_roll", &o.a_roll},
                                                              {"b_roll", &o.b_roll},
                                                              {"a_pitch", &o.a_pitch},
                                                              {"b_pitch", &o.b_pitch},
                                                              {"a_clamp", &o.a_clamp},
                                                              {"b_clamp", &o.b_clamp},
                                                              {"min_radius", &o.min_radius},
                                                              {"theta_neutral", &o.theta_neutral},
                                                              {"force_limit", &o.force_limit}}) {
        set(m, "mapping", key, *field);
      }
      if (m.contains("lower")) vector(m["lower"], "mapping.lower", o.lower);
      if (m.contains("upper")) vector(m["upper"], "mapping.upper", o.upper);
      if (m.contains("force_scale")) vector(m["force_scale"], "mapping.force_scale", o.force_scale);
    }
    if (j.contains("safety")) {
      const json& s = j["safety"];
      only_keys(s, "safety",
                {"max_consecutive_misses", "policy", "force_ramp_time", "max_setpoint_rate",
                 "max_stylus_force", "enable_mask"});
      auto& o = c.safety;
      if (s.contains("max_consecutive_misses")) {
        o.max_consecutive_misses =
            static_cast<int>(number(s["max_consecutive_misses"], "safety.max_consecutive_misses"));
      }
      if (s.contains("policy")) {
        const std::map<std::string, endohaptics::teleop::SafeStatePolicy> policies{
            {"hold_position", endohaptics::teleop::SafeStatePolicy::hold_position},
            {"disable_motors", endohaptics::teleop::SafeStatePolicy::disable_motors},
            {"zero_force", endohaptics::teleop::SafeStatePolicy::zero_force}};
        const auto it = s["policy"].is_string() ? policies.find(s["policy"].get<std::string>())
                                                : policies.end();
        if (it == policies.end()) {
          throw Error(
              "config: 'safety.policy' must be hold_position, disable_motors or "
              "zero_force, got " +
              s["policy"].dump());
        }
        o.policy = it->second;
      }
      set(s, "safety", "force_ramp_time", o.force_ramp_time);
      set(s, "safety", "max_setpoint_rate", o.max_setpoint_rate);
      set(s, "safety", "max_stylus_force", o.max_stylus_force);
      if (s.contains("enable_mask")) {
        const double mask = number(s["enable_mask"], "safety.enable_mask");
        if (!(mask >= 0 && mask <= 15 && mask == static_cast<int>(mask))) {
          throw Error("config: 'safety.enable_mask' must be an integer 0..15, got " +
                      s["enable_mask"].dump());
        }
        o.enable_mask = static_cast<std::uint8_t>(mask);
      }
    }
    if (j.contains("estimator")) {
      const json& e = j["estimator"];
      only_keys(
          e, "estimator",
          {"current_sign", "unit_scale", "friction_level", "output_deadzone", "output_limit"});
      auto& o = c.estimator;
      if (e.contains("current_sign"))
        vector(e["current_sign"], "estimator.current_sign", o.current_sign);
      if (e.contains("unit_scale")) vector(e["unit_scale"], "estimator.unit_scale", o.unit_scale);
      if (e.contains("output_deadzone")) {
        vector(e["output_deadzone"], "estimator.output_deadzone", o.output_deadzone);
      }
      if (e.contains("output_limit"))
        vector(e["output_limit"], "estimator.output_limit", o.output_limit);
      if (e.contains("clamp_model")) {
        if (!e["clamp_model"].is_string()) {
          throw Error("config: 'estimator.clamp_model' must be a file name, got " +
                      e["clamp_model"].dump());
        }
        // Relative to the configuration file's folder.
        const std::filesystem::path model = e["clamp_model"].get<std::string>();
        c.clamp_model =
            (model.is_absolute() ? model : std::filesystem::path(path).parent_path() / model)
                .string();
      }
      if (e.contains("friction_level")) {
        Eigen::Vector4d levels;
        vector(e["friction_level"], "estimator.friction_level", levels);
        for (int i = 0; i < 4; ++i) {
          o.friction[static_cast<std::size_t>(i)] =
              endohaptics::model::JointFriction<double>::simplified(levels[i]);
        }
      }
    }
    if (j.contains("operator")) {
      const json& s = j["operator"];
      only_keys(s, "operator",
                {"theta", "z", "r_open", "r_closed", "open_time", "close_time", "hold_time",
                 "release_time"});
      auto& o = c.operator_script;
      for (auto [key, field] : std::map<const char*, double*>{{"theta", &o.theta},
                                                              {"z", &o.z},
                                                              {"r_open", &o.r_open},
                                                              {"r_closed", &o.r_closed},
                                                              {"open_time", &o.open_time},
                                                              {"close_time", &o.close_time},
                                                              {"hold_time", &o.hold_time},
                                                              {"release_time", &o.release_time}}) {
        set(s, "operator", key, *field);
      }
    }
    if (j.contains("loop")) {
      const json& l = j["loop"];
      only_keys(l, "loop", {"receive_timeout"});
      set(l, "loop", "receive_timeout", c.receive_timeout);
      if (!(c.receive_timeout >= 0 && c.receive_timeout <= 1.0)) {
        throw Error("config: 'loop.receive_timeout' must be in [0, 1] s");
      }
    }
  } catch (const Error& e) {
    throw Error(path + ": " + e.what());
  }
  return c;
}

}  // namespace bridge
