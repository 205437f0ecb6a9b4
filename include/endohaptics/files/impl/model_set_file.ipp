//! @file
//! Function bodies of files/model_set_file.hpp: included at its end (header-only, the default), or
//! compiled once with ENDOHAPTICS_SEPARATE_COMPILATION (core/separate_compilation.hpp).
#pragma once

#include <nlohmann/json.hpp>
#include <system_error>
#include "endohaptics/files/json_text.hpp"
#include "endohaptics/files/model_set_file.hpp"

namespace endohaptics::files {

namespace detail::model_set {

using nlohmann::json;

//! Throws Error "<source>: <what>".
[[noreturn]] inline void fail(const std::string& source, const std::string& what) {
  ENDOHAPTICS_THROW(Error(source + ": " + what));
}

//! `entry` resolved against `base_dir` (a preset and an absolute path stay as they are).
inline std::string resolve(const std::string& entry, const std::filesystem::path& base_dir) {
  const std::filesystem::path p = entry;
  if (entry.starts_with("preset:") || p.is_absolute() || base_dir.empty()) return entry;
  return (base_dir / p).string();
}

}  // namespace detail::model_set

ENDOHAPTICS_DECL ModelSet parse_model_set(std::string_view text, const std::string& source,
                                          const std::filesystem::path& base_dir) {
  namespace ms = detail::model_set;
  namespace jt = detail::json_text;
  const ms::json root =
      jt::parse_strict(text, source, {.max_depth = 8, .needed = "a model set needs 2"});
  if (!root.is_object()) ms::fail(source, "must be a JSON object {...}, got " + jt::show(root));
  for (const auto& [key, value] : root.items()) {
    if (key != "format" && key != "format_version" && key != "instrument" && key != "models") {
      ms::fail(source, "unknown key " + jt::key_name(key) +
                           " (allowed: format, format_version, instrument, models)");
    }
  }
  const auto field = [&](const char* key) -> const ms::json& {
    const auto it = root.find(key);
    if (it == root.end()) ms::fail(source, std::string("missing field \"") + key + "\"");
    return *it;
  };
  const ms::json& format = field("format");
  if (format != model_set_format) {
    ms::fail(source,
             "format: must be \"" + std::string(model_set_format) + "\", got " + jt::show(format));
  }
  const ms::json& version = field("format_version");
  if (!version.is_number_integer() || version.get<long long>() != model_set_format_version) {
    ms::fail(source, "format_version: must be " + std::to_string(model_set_format_version) +
                         " (this library reads version 1), got " + jt::show(version));
  }
  const ms::json& instrument = field("instrument");
  if (!instrument.is_string() || instrument.get_ref<const std::string&>().empty()) {
    ms::fail(source, "instrument: must be the instrument's name (a non-empty string), got " +
                         jt::show(instrument));
  }
  const ms::json& models = field("models");
  if (!models.is_object()) {
    ms::fail(source, "models: must be an object {\"clamp1\": FILE, ...}, got " + jt::show(models));
  }
  ModelSet set;
  set.instrument = instrument.get<std::string>();
  set.source = source;
  for (const auto& [key, value] : models.items()) {
    bool found = false;
    for (const protocol::Motor m : model_set_motors) {
      if (key != protocol::to_string(m)) continue;
      found = true;
      if (!value.is_string() || value.get_ref<const std::string&>().empty()) {
        ms::fail(source,
                 "models." + key +
                     ": must be a model file or \"preset:NAME\" (a non-empty string), got " +
                     jt::show(value));
      }
      set.models[static_cast<std::size_t>(m)] = ms::resolve(value.get<std::string>(), base_dir);
    }
    if (!found) {
      ms::fail(source, "unknown key " + jt::key_name("models." + key) +
                           " (allowed in 'models': clamp1, clamp2, roll, pitch)");
    }
  }
  return set;
}

ENDOHAPTICS_DECL ModelSet load_model_set(const std::filesystem::path& path) {
  std::error_code ec;
  if (std::filesystem::is_directory(path, ec)) {
    const std::filesystem::path file = path / model_set_file_name;
    if (std::filesystem::exists(file, ec)) return load_model_set(file);
    ModelSet set;
    set.instrument =
        path.filename().empty() ? path.parent_path().filename().string() : path.filename().string();
    set.source = path;
    bool any = false;
    for (const protocol::Motor m : model_set_motors) {
      const std::filesystem::path f = path / (std::string(protocol::to_string(m)) + ".json");
      if (std::filesystem::exists(f, ec)) {
        set.models[static_cast<std::size_t>(m)] = f.string();
        any = true;
      }
    }
    if (!any) {
      detail::model_set::fail("model set " + path.string(),
                              "the directory holds no model_set.json and no clamp1.json, "
                              "clamp2.json, roll.json or pitch.json");
    }
    return set;
  }
  const std::string text = detail::json_text::read_bounded(
      path, model_set_max_bytes, "model set file", "files::model_set_max_bytes");
  return parse_model_set(text, "model set " + path.string(), path.parent_path());
}

ENDOHAPTICS_DECL ModelSet load_instrument_model_set(const std::filesystem::path& folder,
                                                    const std::string& instrument) {
  const auto plain = [](char c) {
    return (c >= 'a' && c <= 'z') || (c >= 'A' && c <= 'Z') || (c >= '0' && c <= '9') || c == '.' ||
           c == '_' || c == '-';
  };
  bool ok = !instrument.empty() && instrument.size() <= 100 && instrument.front() != '.';
  for (const char c : instrument) ok = ok && plain(c);
  if (!ok) {
    ENDOHAPTICS_THROW(Error("instrument '" + detail::json_text::excerpt(instrument) +
                            "': an instrument name is letters, digits, '.', '_' and '-' (at most "
                            "100, not starting with '.')"));
  }
  std::error_code ec;
  const std::filesystem::path file = folder / (instrument + ".json");
  const std::filesystem::path dir = folder / instrument;
  const bool has_file = std::filesystem::exists(file, ec);
  const bool has_dir = std::filesystem::is_directory(dir, ec);
  if (has_file && has_dir) {
    ENDOHAPTICS_THROW(Error("instrument '" + instrument + "': both " + file.string() + " and " +
                            dir.string() + "/ exist: keep one"));
  }
  if (!has_file && !has_dir) {
    ENDOHAPTICS_THROW(Error("instrument '" + instrument + "': no model set " + file.string() +
                            " or " + dir.string() + "/"));
  }
  ModelSet set = load_model_set(has_file ? file : dir);
  if (set.instrument != instrument) {
    ENDOHAPTICS_THROW(Error(set.source.string() + ": instrument: is '" +
                            detail::json_text::excerpt(set.instrument) + "', the set chosen for '" +
                            instrument + "' must name it"));
  }
  return set;
}

ENDOHAPTICS_DECL BridgeModelSet bridge_model_set(const ModelSet& set,
                                                 const std::array<bool, 4>& fed_back) {
  using protocol::Motor;
  const std::string source = set.source.string();
  std::string missing;
  for (const Motor m : model_set_motors) {
    if (fed_back[static_cast<std::size_t>(m)] && set.model(m).empty()) {
      missing += (missing.empty() ? "" : ", ") + std::string(protocol::to_string(m));
    }
  }
  if (!missing.empty()) {
    detail::model_set::fail(
        source, "instrument '" + set.instrument + "': no model for " + missing +
                    ", whose force the stylus renders (mapping.force_scale != 0): give one, or "
                    "set that channel's force_scale to 0");
  }
  BridgeModelSet out{estimation::bridge_force_models(), {}};
  out.description = "instrument " + set.instrument + " (" + source + "):";
  bool first = true;
  for (const Motor m : model_set_motors) {
    const std::string name(protocol::to_string(m));
    const std::string where = source + ": models." + name;
    const bool clamp = m == Motor::clamp1 || m == Motor::clamp2;
    const std::string own_preset = clamp ? "preset:yaw2016" : "preset:" + name + "2016";
    std::string entry = set.model(m);
    std::string said;
    if (entry.empty()) {
      entry = own_preset;
      said = own_preset + " (none in the set, no force feedback)";
    } else if (entry.starts_with("preset:")) {
      said = entry;
    }
    estimation::BridgeJointModel& slot =
        m == Motor::roll
            ? out.models.roll
            : (m == Motor::pitch ? out.models.pitch
                                 : (m == Motor::clamp1 ? out.models.clamp1 : out.models.clamp2));
    if (entry.starts_with("preset:")) {
      if (entry == own_preset) {
        // bridge_force_models() holds every joint's own 2016 model already
      } else if (clamp && entry == "preset:clamp2016-as-run") {
        slot = estimation::BridgeJointModel(estimation::Clamp2016AsRun<double>{});
      } else {
        detail::model_set::fail(
            where, "unknown preset '" + detail::json_text::excerpt(entry) + "' (valid: " +
                       (clamp ? "preset:yaw2016, preset:clamp2016-as-run" : own_preset) +
                       ", or a model file)");
      }
    } else {
      try {
        const ModelFile file = load_model(entry);
        slot = bridge_joint_model(file, "model file " + entry);
        said = std::string(to_string(file.kind())) + " (" + entry + ")";
      } catch (const Error& e) {
        detail::model_set::fail(where, e.what());
      }
    }
    out.description += std::string(first ? " " : ", ") + name + " " + said;
    first = false;
  }
  return out;
}

}  // namespace endohaptics::files
