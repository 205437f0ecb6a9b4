//! @file
//! Function bodies of files/bridge_config.hpp: included at its end (header-only, the default), or
//! compiled once with ENDOHAPTICS_SEPARATE_COMPILATION (core/separate_compilation.hpp).
#pragma once

#include <map>
#include <nlohmann/json.hpp>
#include <set>
#include "endohaptics/files/bridge_config.hpp"
#include "endohaptics/files/json_text.hpp"

namespace endohaptics::files {

namespace detail::bridge_config {

using nlohmann::json;

using json_text::excerpt;
using json_text::key_name;
using json_text::show;

//! The file's sections in file order, each the field list of one library struct (its
//! `for_each_field`: names and bounds are the struct's own): `f(section, config struct)`.
//! "estimator" has three keys more, clamp_model, model_sets and instrument (BridgeConfig's).
template <typename Config, typename F>
void for_each_section(Config& c, F&& f) {
  f("mapping", c.mapping);
  f("safety", c.loop.safety);
  f("plausibility", c.loop.safety.plausibility);
  f("estimator", c.estimator);
  f("operator", c.operator_script);
  f("loop", c.loop);
  f("passivity", c.loop.passivity);
}

//! The section whose struct's validation names `owner` (ParameterError::owner()), or "".
inline std::string_view section_of(std::string_view owner) {
  if (owner == "CylindricalMapper") return "mapping";
  if (owner == "SafetyConfig") return "safety";
  if (owner == "StatePlausibility") return "plausibility";
  if (owner == "ForceEstimator") return "estimator";
  if (owner == "OperatorScript") return "operator";
  if (owner == "TeleopLoopConfig") return "loop";
  if (owner == "PassivityConfig") return "passivity";
  return {};
}

//! The bound of the mapping's force limits in the bridge: at most the Touch's peak
//! (SafetyBounds::max_stylus_force), a relation of the mapping to the device it drives.
inline constexpr Bound device_force_bound =
    Bound::above(0, teleop::SafetyBounds::max_stylus_force, "N");
//! The bound of the mapping's joint ranges in the bridge: within the EndoWrist's joint limit
//! (SafetyBounds::joint_limit), as the safety ranges are.
inline constexpr Bound device_angle_bound =
    Bound::in(-teleop::SafetyBounds::joint_limit, teleop::SafetyBounds::joint_limit, "rad")
        .described("in [-pi, pi] rad");

//! "section.key".
inline std::string dotted(std::string_view section, std::string_view key) {
  return std::string(section) + "." + std::string(key);
}

//! Throws Error "<source>: <key>: <what>".
[[noreturn]] inline void fail(std::string_view source, std::string_view key,
                              const std::string& what) {
  ENDOHAPTICS_THROW(Error(std::string(source) + ": " + std::string(key) + ": " + what));
}

//! "an integer in [lo, hi]" for an integer field, else the bound's description.
template <typename T>
std::string describe(const Bound& bound) {
  if constexpr (std::is_integral_v<T>) {
    return "an integer in [" + std::to_string(static_cast<long long>(bound.lo)) + ", " +
           std::to_string(static_cast<long long>(bound.hi)) + "]";
  } else {
    return bound.describe();
  }
}

//! A number of a field's value, by kind: plain, a vector (element access), a duration.
template <typename T>
concept Duration = requires(const T& d) {
  std::chrono::duration<double>(d).count();
};

//! Visitor: the field names of a section, in list order.
struct KeyCollector {
  std::vector<std::string>& keys;  //!< the names
  template <typename T>
  void operator()(std::string_view name, T&&, const Bound&) const {
    keys.emplace_back(name);
  }
};

//! Visitor: reads the keys present in one section's object into its struct, each checked
//! against its field's bound as it is read (file order).
struct Reader {
  const json& object;        //!< the section, an object with known keys only
  std::string_view source;   //!< for messages
  std::string_view section;  //!< e.g. "safety"

  [[nodiscard]] double number(const json& j, const std::string& key, const Bound& bound) const {
    if (!j.is_number())
      fail(source, key, "must be a number (" + bound.describe() + "), got " + show(j));
    const double value = j.get<double>();
    if (!bound.contains(value)) {
      fail(source, key,
           "must be " + bound.describe() + ", got " + endohaptics::detail::format_number(value));
    }
    return value;
  }
  template <typename T>
  void read_integer(const json& j, const std::string& key, T& out, const Bound& bound) const {
    const auto lo = static_cast<long long>(bound.lo);
    const auto hi = static_cast<long long>(bound.hi);
    const auto bad = [&] {
      fail(source, key, "must be " + describe<T>(bound) + ", got " + show(j));
    };
    // Compared in the type the parser chose, converted only once known to be in range.
    if (j.is_number_unsigned()) {
      const auto u = j.get<std::uint64_t>();
      if (u > static_cast<std::uint64_t>(hi)) bad();
      out = static_cast<T>(u);
    } else if (j.is_number_integer()) {
      const auto i = j.get<std::int64_t>();
      if (i < lo || i > hi) bad();
      out = static_cast<T>(i);
    } else if (j.is_number_float()) {
      const double d = j.get<double>();
      if (!(std::isfinite(d) && d == std::trunc(d) && d >= static_cast<double>(lo) &&
            d <= static_cast<double>(hi))) {
        bad();
      }
      out = static_cast<T>(static_cast<long long>(d));
    } else {
      bad();
    }
  }
  template <typename T>
  void operator()(std::string_view name, T&& value, const Bound& bound) const {
    using V = std::remove_cvref_t<T>;
    const auto it = object.find(std::string(name));
    if (it == object.end()) return;
    const json& j = *it;
    const std::string key = dotted(section, name);
    if constexpr (std::is_same_v<V, bool>) {
      if (!j.is_boolean()) fail(source, key, "must be true or false, got " + show(j));
      value = j.get<bool>();
    } else if constexpr (NamedEnum<V>) {
      if (j.is_string()) {
        for (const auto& [label, e] : enumerators(value)) {
          if (j.get_ref<const std::string&>() == label) {
            value = e;
            return;
          }
        }
      }
      fail(source, key, "must be " + enumerator_list(value) + ", got " + show(j));
    } else if constexpr (std::is_integral_v<V>) {
      read_integer(j, key, value, bound);
    } else if constexpr (std::is_floating_point_v<V>) {
      value = static_cast<V>(number(j, key, bound));
    } else if constexpr (Duration<V>) {
      // The bound is finite (at most 1 s): the conversion to ns cannot overflow.
      value = std::chrono::duration_cast<V>(
          std::chrono::nanoseconds(std::llround(number(j, key, bound) * 1e9)));
    } else {
      const auto n = static_cast<std::size_t>(value.size());
      if (!j.is_array() || j.size() != n) {
        fail(source, key,
             "must be an array of " + std::to_string(n) + " numbers, each " + bound.describe() +
                 ", got " + show(j));
      }
      for (std::size_t i = 0; i < n; ++i) {
        const double x = number(j[i], key + "[" + std::to_string(i) + "]", bound);
        if constexpr (requires { value.set(0L, x); }) {
          value.set(static_cast<long>(i), x);
        } else {
          value[static_cast<Eigen::Index>(i)] =
              static_cast<std::remove_cvref_t<decltype(value[0])>>(x);
        }
      }
    }
  }
};

//! Visitor: writes every field of one section into `out`.
struct Writer {
  nlohmann::ordered_json& out;  //!< the section's object
  template <typename T>
  void operator()(std::string_view name, T&& value, const Bound&) const {
    using V = std::remove_cvref_t<T>;
    const std::string key(name);
    if constexpr (std::is_same_v<V, bool>) {
      out[key] = value;
    } else if constexpr (NamedEnum<V>) {
      out[key] = std::string(enumerator_name(value));
    } else if constexpr (std::is_integral_v<V>) {
      out[key] = static_cast<long long>(value);
    } else if constexpr (std::is_floating_point_v<V>) {
      out[key] = static_cast<double>(value);
    } else if constexpr (Duration<V>) {
      out[key] = std::chrono::duration<double>(value).count();
    } else {
      auto a = nlohmann::ordered_json::array();
      for (long i = 0; i < static_cast<long>(value.size()); ++i) {
        a.push_back(static_cast<double>(value[i]));
      }
      out[key] = a;
    }
  }
};

//! Visitor: checks every field of one section of a built BridgeConfig against its bound.
struct Checker {
  std::string_view source;   //!< for messages
  std::string_view section;  //!< e.g. "safety"

  void check(const std::string& key, double value, const std::string& rule, bool ok) const {
    if (!ok)
      fail(source, key, "must be " + rule + ", got " + endohaptics::detail::format_number(value));
  }
  template <typename T>
  void operator()(std::string_view name, const T& value, const Bound& bound) const {
    const std::string key = dotted(section, name);
    if constexpr (std::is_same_v<T, bool>) {
      return;  // both values are allowed
    } else if constexpr (NamedEnum<T>) {
      if (enumerator_name(value).empty()) {
        fail(source, key,
             "is not one of " + enumerator_list(value) + " (" +
                 std::to_string(static_cast<long long>(value)) + ")");
      }
    } else if constexpr (std::is_arithmetic_v<T>) {
      check(key, static_cast<double>(value), describe<T>(bound),
            bound.contains(static_cast<double>(value)));
    } else if constexpr (Duration<T>) {
      const double seconds = std::chrono::duration<double>(value).count();
      check(key, seconds, bound.describe(), bound.contains(seconds));
    } else {
      for (long i = 0; i < static_cast<long>(value.size()); ++i) {
        const auto x = static_cast<double>(value[i]);
        check(key + "[" + std::to_string(i) + "]", x, bound.describe(), bound.contains(x));
      }
    }
  }
};

//! Parses `text` as JSON (comments allowed): nesting limited as it parses, duplicate keys
//! refused anywhere (files/json_text.hpp).
inline json parse(std::string_view text, std::string_view source) {
  return json_text::parse_strict(
      text, source,
      {.max_depth = bridge_config_max_depth, .needed = "the bridge configuration needs 3"});
}

//! Runs a library validator; a ParameterError becomes "<source>: <section>.<field>: must be
//! <rule>, got <value>" (its owner's section), another Error gets "<source>: <key>: " in front.
template <typename F>
void with_prefix(std::string_view source, std::string_view key, F&& validate) {
  try {
    validate();
  } catch (const ParameterError& e) {
    const std::string_view section = section_of(e.owner());
    if (section.empty()) fail(source, key, e.what());
    fail(source, dotted(section, e.field()), "must be " + e.rule() + ", got " + e.value());
  } catch (const Error& e) {
    fail(source, key, e.what());
  }
}

}  // namespace detail::bridge_config

ENDOHAPTICS_DECL BridgeModelSet bridge_config_force_models(const BridgeConfig& config) {
  if (!config.instrument.empty()) {
    if (!config.clamp_model.empty()) {
      ENDOHAPTICS_THROW(Error(
          "instrument '" + config.instrument + "' and clamp_model '" + config.clamp_model.string() +
          "': give one (the instrument's model set names its clamp models), not both"));
    }
    if (config.model_sets.empty()) {
      ENDOHAPTICS_THROW(Error("instrument '" + config.instrument +
                              "': no estimator.model_sets folder to find its model set in"));
    }
    return bridge_model_set(load_instrument_model_set(config.model_sets, config.instrument),
                            force_feedback_motors(config.mapping));
  }
  const std::string name = config.clamp_model.string();
  if (name.starts_with("preset:")) {  // the clamp preset's one definition
    return {estimation::preset_force_models(estimation::clamp_preset(name.substr(7))),
            "clamp model " + name +
                " on both clamps, roll preset:roll2016, pitch "
                "preset:pitch2016"};
  }
  if (!name.empty()) {
    const ModelFile file = load_model(config.clamp_model);
    return {estimation::bridge_force_models(bridge_joint_model(file, "model file " + name)),
            "clamp model " + std::string(to_string(file.kind())) + " (" + name +
                ") on both clamps, roll preset:roll2016, pitch preset:pitch2016"};
  }
  return {estimation::bridge_force_models(),
          "the 2016 models: clamp1 preset:yaw2016, clamp2 preset:yaw2016, roll "
          "preset:roll2016, pitch preset:pitch2016"};
}

ENDOHAPTICS_DECL void validate_bridge_config(const BridgeConfig& config, std::string_view source) {
  namespace bc = detail::bridge_config;
  bc::for_each_section(config, [&](std::string_view section, const auto& part) {
    std::remove_cvref_t<decltype(part)>::for_each_field(part, bc::Checker{source, section});
  });
  // The mapping's force limits against the device (the Touch's peak).
  bc::Checker mapping{source, "mapping"};
  mapping.check("mapping.force_limit", config.mapping.force_limit,
                bc::device_force_bound.describe(),
                bc::device_force_bound.contains(config.mapping.force_limit));
  for (int i = 0; i < 4; ++i) {
    for (const auto& [name, range] :
         {std::pair{"lower", &config.mapping.lower}, std::pair{"upper", &config.mapping.upper}}) {
      mapping.check("mapping." + std::string(name) + "[" + std::to_string(i) + "]", (*range)[i],
                    bc::device_angle_bound.describe(),
                    bc::device_angle_bound.contains((*range)[i]));
    }
  }
  for (int i = 0; i < 3; ++i) {
    mapping.check("mapping.channel_limit[" + std::to_string(i) + "]",
                  config.mapping.channel_limit[i], bc::device_force_bound.describe(),
                  bc::device_force_bound.contains(config.mapping.channel_limit[i]));
  }
  // Cross-field checks, named by the section they concern.
  bc::with_prefix(source, "safety", [&] { config.loop.validate(); });
  bc::with_prefix(source, "mapping",
                  [&] { (void)kinematics::CylindricalMapper<double>(config.mapping); });
  bc::with_prefix(source, "operator", [&] { config.operator_script.validate(); });
  // The force models as the bridge will run them, and the estimator they make with the settings.
  std::optional<estimation::BridgeForceModels> models;
  const char* models_key = !config.instrument.empty()    ? "estimator.instrument"
                           : !config.clamp_model.empty() ? "estimator.clamp_model"
                                                         : "estimator";
  bc::with_prefix(source, models_key, [&] { models = bridge_config_force_models(config).models; });
  bc::with_prefix(source, "estimator", [&] {
    (void)estimation::BridgeForceEstimator(
        *models, estimation::bridge_estimator_settings(config.estimator, *models));
  });
}

ENDOHAPTICS_DECL BridgeConfig parse_bridge_config(std::string_view text, std::string_view source,
                                                  const std::filesystem::path& base_dir) {
  namespace bc = detail::bridge_config;
  const bc::json root = bc::parse(text, source);
  if (!root.is_object()) {
    ENDOHAPTICS_THROW(
        Error(std::string(source) + ": must be a JSON object {...}, got " + bc::show(root)));
  }
  BridgeConfig config;
  std::map<std::string, std::vector<std::string>, std::less<>> schema;  // section -> keys
  std::vector<std::string> sections;
  bc::for_each_section(config, [&](std::string_view section, auto& part) {
    sections.emplace_back(section);
    std::vector<std::string>& keys = schema[std::string(section)];
    std::remove_cvref_t<decltype(part)>::for_each_field(part, bc::KeyCollector{keys});
    if (section == "estimator") {
      for (const char* k : {"clamp_model", "model_sets", "instrument"}) keys.emplace_back(k);
    }
  });
  auto list = [](const auto& names) {
    std::string out;
    for (const auto& n : names) out += (out.empty() ? "" : ", ") + std::string(n);
    return out;
  };
  for (const auto& [section, value] : root.items()) {
    const auto known = schema.find(section);
    if (known == schema.end()) {
      ENDOHAPTICS_THROW(Error(std::string(source) + ": unknown key " + bc::key_name(section) +
                              " (allowed: " + list(sections) + ")"));
    }
    if (!value.is_object()) {
      bc::fail(source, section, "must be an object {...}, got " + bc::show(value));
    }
    for (const auto& [key, ignored] : value.items()) {
      bool found = false;
      for (const auto& k : known->second) found = found || k == key;
      if (!found) {
        ENDOHAPTICS_THROW(Error(std::string(source) + ": unknown key " +
                                bc::key_name(section + "." + key) + " (allowed in '" + section +
                                "': " + list(known->second) + ")"));
      }
    }
  }
  bc::for_each_section(config, [&](std::string_view section, auto& part) {
    const auto it = root.find(std::string(section));
    if (it == root.end()) return;
    std::remove_cvref_t<decltype(part)>::for_each_field(part, bc::Reader{*it, source, section});
    if (section != "estimator") return;
    for (const char* key : {"model_sets", "instrument"}) {
      const auto v = it->find(key);
      if (v == it->end()) continue;
      if (!v->is_string() || v->get_ref<const std::string&>().empty()) {
        bc::fail(source, bc::dotted("estimator", key),
                 std::string("must be ") +
                     (key == std::string_view("instrument") ? "the instrument's name"
                                                            : "the folder of model sets") +
                     " (a non-empty string), got " + bc::show(*v));
      }
      if (key == std::string_view("instrument")) {
        config.instrument = v->get<std::string>();
      } else {
        const std::filesystem::path p = v->get<std::string>();
        config.model_sets = p.is_absolute() || base_dir.empty() ? p : base_dir / p;
      }
    }
    const auto model = it->find("clamp_model");
    if (model == it->end()) return;
    if (!model->is_string() || model->get_ref<const std::string&>().empty()) {
      bc::fail(source, "estimator.clamp_model",
               "must be the name of a model file (a non-empty string), got " + bc::show(*model));
    }
    const std::filesystem::path p = model->get<std::string>();
    const bool preset = model->get_ref<const std::string&>().starts_with("preset:");
    config.clamp_model = p.is_absolute() || base_dir.empty() || preset ? p : base_dir / p;
  });
  validate_bridge_config(config, source);
  return config;
}

ENDOHAPTICS_DECL BridgeConfig load_bridge_config(const std::filesystem::path& path) {
  const std::string text = detail::json_text::read_bounded(
      path, bridge_config_max_bytes, "configuration file",
      "files::bridge_config_max_bytes; a complete one is under 2 kB");
  return parse_bridge_config(text, path.string(), path.parent_path());
}

ENDOHAPTICS_DECL std::string bridge_config_json(const BridgeConfig& config, int indent) {
  namespace bc = detail::bridge_config;
  nlohmann::ordered_json out = nlohmann::ordered_json::object();
  bc::for_each_section(config, [&](std::string_view section, const auto& part) {
    nlohmann::ordered_json& object = out[std::string(section)] = nlohmann::ordered_json::object();
    std::remove_cvref_t<decltype(part)>::for_each_field(part, bc::Writer{object});
    if (section == "estimator" && !config.clamp_model.empty()) {
      object["clamp_model"] = config.clamp_model.string();
    }
    if (section == "estimator" && !config.model_sets.empty()) {
      object["model_sets"] = config.model_sets.string();
    }
    if (section == "estimator" && !config.instrument.empty()) {
      object["instrument"] = config.instrument;
    }
  });
  return out.dump(indent);
}

}  // namespace endohaptics::files
