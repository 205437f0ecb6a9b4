//! @file
//! Function bodies of files/model_file.hpp: included at its end (header-only, the default), or
//! compiled once with ENDOHAPTICS_SEPARATE_COMPILATION (core/separate_compilation.hpp).
#pragma once

#include "endohaptics/files/model_file.hpp"

namespace endohaptics::files {
namespace detail::model_file {

// The inputs a joint model takes: (current, velocity), and for an observer that refers its
// current to the command, that command third.
inline std::size_t joint_model_inputs(const ModelFile& m) { return m.current_reference ? 3 : 2; }

ENDOHAPTICS_DECL model::DynamicStateSpace<> joint_model_placeholder(Eigen::Index nu,
                                                                    double sample_time) {
  return model::DynamicStateSpace<>(Eigen::MatrixXd::Zero(1, 1), Eigen::MatrixXd::Zero(1, nu),
                                    Eigen::MatrixXd::Zero(1, 1), Eigen::MatrixXd::Zero(1, nu),
                                    sample_time);
}

ENDOHAPTICS_DECL void require_linear(const ModelFile& f, const std::string& where) {
  if (f.is_joint_model()) {
    fail(where + ": kind \"" + std::string(to_string(f.kind())) +
         "\" is a joint force model, not a linear or Hammerstein-Wiener model (load it with "
         "load_model and run it as its estimation type)");
  }
}

ENDOHAPTICS_DECL void require_kind(const ModelFile& f, ModelKind kind, const std::string& where) {
  if (f.kind() != kind) {
    fail(where + ": the model file is of kind \"" + std::string(to_string(f.kind())) +
         "\", not \"" + std::string(to_string(kind)) + "\"");
  }
}

ENDOHAPTICS_DECL void validate(const ModelFile& m, const std::string& where) {
  const model::DynamicStateSpace<>& ss = m.state_space;
  if (!(m.free_motion_threshold >= 0.0 && m.free_motion_threshold <= ModelFile::max_parameter)) {
    fail(where + ": free_motion_threshold must be in [0, " +
         format_number(ModelFile::max_parameter) + "] (output units), got " +
         format_number(m.free_motion_threshold));
  }
  model::check_friction_play(m.current_play, m.current_play_slide, m.current_play_viscous, where);
  if (m.current_play_viscous != 0.0 && m.inputs.size() < 2) {
    fail(where + ": current_play_viscous needs the velocity as input 1");
  }
  if (m.current_reference && m.kind() != ModelKind::push_load_observer &&
      m.kind() != ModelKind::bidirectional_load_observer) {
    fail(where + ": kind \"" + std::string(to_string(m.kind())) +
         "\" has no current_reference (only the observers refer their current to a command)");
  }
  if (m.is_joint_model()) {
    const std::string kind(to_string(m.kind()));
    const std::size_t nu = joint_model_inputs(m);
    if (m.inputs.size() != nu || m.outputs.size() != 1) {
      fail(where + ": kind \"" + kind + "\" needs " +
           (nu == 3 ? "3 inputs (current, velocity, current command: its command_gain is not 0)"
                    : "2 inputs (current, velocity)") +
           " and 1 output, got " + std::to_string(m.inputs.size()) + " and " +
           std::to_string(m.outputs.size()));
    }
    if (m.is_hammerstein_wiener()) {
      fail(where + ": kind \"" + kind + "\" has no input or output nonlinearity");
    }
    if (m.free_motion_threshold != 0.0) {
      fail(where + ": kind \"" + kind + "\" has no free_motion_threshold (linear kinds only)");
    }
    if (m.current_play != 0.0) {
      fail(where + ": kind \"" + kind + "\" has no current_play (linear kinds only)");
    }
    if (ss.state_size() != 1 || ss.input_size() != static_cast<Eigen::Index>(nu) ||
        ss.output_size() != 1 || !ss.A().isZero(0.0) || !ss.B().isZero(0.0) ||
        !ss.C().isZero(0.0) || !ss.D().isZero(0.0) || !ss.state().isZero(0.0)) {
      fail(where + ": kind \"" + kind +
           "\": the linear block must be the placeholder (1 state, one column per input, 1 "
           "output, all zero)");
    }
    std::visit(
        [&](const auto& p) {
          if constexpr (!std::is_same_v<std::decay_t<decltype(p)>, std::monostate>) {
            if (p.sample_time != ss.sample_time()) {
              fail(where + ": the parameters' sample_time " + format_number(p.sample_time) +
                   " s is not the file's " + format_number(ss.sample_time()) + " s");
            }
            validate_parameters(p, where, "parameters");
          }
        },
        m.parameters);
    if (m.current_reference) {
      validate_parameters(*m.current_reference, where, "current_reference");
    }
  }

  const auto nu = static_cast<std::size_t>(ss.input_size());
  const auto ny = static_cast<std::size_t>(ss.output_size());
  auto signals = [&](const char* field, const std::vector<SignalInfo>& v, std::size_t count,
                     const char* what) {
    if (v.size() != count) {
      fail(where + ": field \"" + field + "\" has " + std::to_string(v.size()) +
           " entries, the model has " + std::to_string(count) + " " + what);
    }
  };
  signals("inputs", m.inputs, nu, "inputs (columns of B)");
  signals("outputs", m.outputs, ny, "outputs (rows of C)");
  for (Eigen::Index i = 0; i < ss.state().size(); ++i) {
    if (!std::isfinite(ss.state()[i])) {
      fail(where + ": field \"x0[" + std::to_string(i) + "]\" is not finite (" +
           format_number(ss.state()[i]) + ")");
    }
  }
  auto maps = [&](const char* field, const std::vector<StaticMap>& v, std::size_t count,
                  const char* what) {
    if (v.size() != count) {
      fail(where + ": field \"" + field + "\" has " + std::to_string(v.size()) +
           " entries, expected " + std::to_string(count) + " (" + what + ")");
    }
    for (std::size_t i = 0; i < v.size(); ++i) {
      const std::string at = where + ": field \"" + field + "[" + std::to_string(i) + "]\"";
      if (v[i].kind == StaticMapKind::none) continue;
      if (!std::isfinite(v[i].lower) || !std::isfinite(v[i].upper)) {
        fail(at + ": breakpoints must be finite, got [" + format_number(v[i].lower) + ", " +
             format_number(v[i].upper) + "]");
      }
      if (!(v[i].lower <= v[i].upper)) {
        fail(at + ": lower " + format_number(v[i].lower) + " is greater than upper " +
             format_number(v[i].upper));
      }
    }
  };
  if (m.is_hammerstein_wiener()) {
    maps("input_nonlinearity", m.input_nonlinearity, nu, "inputs");
    maps("output_nonlinearity", m.output_nonlinearity, ny, "outputs");
  }
  for (double f : m.provenance.fit_percent) {
    if (std::isnan(f)) fail(where + ": field \"provenance.fit_percent\" holds NaN");
  }
}

ENDOHAPTICS_DECL json matrix_to_json(const Eigen::MatrixXd& M) {
  json rows = json::array();
  for (Eigen::Index i = 0; i < M.rows(); ++i) {
    json row = json::array();
    for (Eigen::Index j = 0; j < M.cols(); ++j) row.push_back(M(i, j));
    rows.push_back(std::move(row));
  }
  return rows;
}

ENDOHAPTICS_DECL double number(const json& value, const std::string& where,
                               const std::string& name) {
  if (!value.is_number()) {
    fail(where + ": field \"" + name + "\" is not a number (" + detail::json_text::show(value) +
         ")");
  }
  return value.get<double>();
}

ENDOHAPTICS_DECL std::string text(const json& value, const std::string& where,
                                  const std::string& name) {
  if (!value.is_string()) {
    fail(where + ": field \"" + name + "\" is not a string (" + detail::json_text::show(value) +
         ")");
  }
  return value.get<std::string>();
}

ENDOHAPTICS_DECL int integer(const json& value, const std::string& where, const std::string& name,
                             int min, int max) {
  if (!value.is_number_integer()) {
    fail(where + ": field \"" + name + "\" is not an integer (" + detail::json_text::show(value) +
         ")");
  }
  bool in_range = false;
  if (value.is_number_unsigned()) {
    const auto v = value.get<std::uint64_t>();
    in_range =
        max >= 0 && v <= static_cast<std::uint64_t>(max) && static_cast<std::int64_t>(v) >= min;
  } else {
    const auto v = value.get<std::int64_t>();
    in_range = v >= min && v <= max;
  }
  if (!in_range) {
    fail(where + ": field \"" + name + "\" is " + detail::json_text::show(value) + ", outside [" +
         std::to_string(min) + ", " + std::to_string(max) + "]");
  }
  return static_cast<int>(value.get<std::int64_t>());
}

ENDOHAPTICS_DECL Eigen::MatrixXd matrix_from_json(const json& object, const char* key,
                                                  Eigen::Index rows, Eigen::Index cols,
                                                  const char* row_name, const char* col_name,
                                                  const std::string& where) {
  const json& value = field(object, key, where);
  const std::string name(key);
  if (!value.is_array()) fail(where + ": field \"" + name + "\" is not an array of rows");
  if (static_cast<Eigen::Index>(value.size()) != rows) {
    fail(where + ": field \"" + name + "\" has " + std::to_string(value.size()) +
         " rows, expected " + std::to_string(rows) + " (" + row_name + ")");
  }
  // Every row's length first: the allocation below is then bounded by what the file holds (a
  // file cannot ask for rows x cols doubles it does not contain).
  for (Eigen::Index i = 0; i < rows; ++i) {
    const json& row = value[static_cast<std::size_t>(i)];
    if (!row.is_array() || static_cast<Eigen::Index>(row.size()) != cols) {
      fail(where + ": field \"" + name + "[" + std::to_string(i) + "]\" has " +
           (row.is_array() ? std::to_string(row.size()) : std::string("no")) +
           " columns, expected " + std::to_string(cols) + " (" + col_name + ")");
    }
  }
  Eigen::MatrixXd M(rows, cols);
  for (Eigen::Index i = 0; i < rows; ++i) {
    const json& row = value[static_cast<std::size_t>(i)];
    const std::string row_field = name + "[" + std::to_string(i) + "]";
    for (Eigen::Index j = 0; j < cols; ++j) {
      const std::string entry = row_field + "[" + std::to_string(j) + "]";
      M(i, j) = number(row[static_cast<std::size_t>(j)], where, entry);
      if (!std::isfinite(M(i, j))) {
        fail(where + ": field \"" + entry + "\" is not finite (" + format_number(M(i, j)) + ")");
      }
    }
  }
  return M;
}

ENDOHAPTICS_DECL std::vector<SignalInfo> signals_from_json(const json& object, const char* key,
                                                           const std::string& where) {
  const json& value = field(object, key, where);
  if (!value.is_array()) fail(where + ": field \"" + key + "\" is not an array");
  std::vector<SignalInfo> out;
  for (std::size_t i = 0; i < value.size(); ++i) {
    const std::string name = std::string(key) + "[" + std::to_string(i) + "]";
    if (!value[i].is_object()) fail(where + ": field \"" + name + "\" is not an object");
    out.push_back({text(field(value[i], "name", where + ": " + name), where, name + ".name"),
                   text(field(value[i], "unit", where + ": " + name), where, name + ".unit")});
  }
  return out;
}

ENDOHAPTICS_DECL void add_linear_block(json& j, const ModelFile& m) {
  const model::DynamicStateSpace<>& ss = m.state_space;
  j["A"] = matrix_to_json(ss.A());
  j["B"] = matrix_to_json(ss.B());
  j["C"] = matrix_to_json(ss.C());
  j["D"] = matrix_to_json(ss.D());
  j["x0"] = std::vector<double>(ss.state().data(), ss.state().data() + ss.state().size());
  if (m.free_motion_threshold > 0.0) j["free_motion_threshold"] = m.free_motion_threshold;
  if (m.current_play > 0.0) j["current_play"] = m.current_play;
  if (m.current_play_slide) j["current_play_slide"] = *m.current_play_slide;
  if (m.current_play_viscous != 0.0) j["current_play_viscous"] = m.current_play_viscous;
  if (m.is_hammerstein_wiener()) {
    j["input_nonlinearity"] = json::array();
    for (const auto& map : m.input_nonlinearity)
      j["input_nonlinearity"].push_back(map_to_json(map));
    j["output_nonlinearity"] = json::array();
    for (const auto& map : m.output_nonlinearity) {
      j["output_nonlinearity"].push_back(map_to_json(map));
    }
  }
}

ENDOHAPTICS_DECL ModelProvenance provenance_from_json(const json& j, const std::string& where) {
  ModelProvenance out;
  const auto& p = field(j, "provenance", where);
  if (!p.is_object()) fail(where + ": field \"provenance\" is not an object");
  const std::string pw = where + ": provenance";
  out.method = text(field(p, "method", pw), where, "provenance.method");
  out.order = integer(field(p, "order", pw), where, "provenance.order");
  out.block_rows = integer(field(p, "block_rows", pw), where, "provenance.block_rows");
  out.date = text(field(p, "date", pw), where, "provenance.date");
  out.notes = text(field(p, "notes", pw), where, "provenance.notes");
  const auto& files = field(p, "files", pw);
  const auto& fit = field(p, "fit_percent", pw);
  if (!files.is_array()) fail(where + ": field \"provenance.files\" is not an array");
  if (!fit.is_array()) fail(where + ": field \"provenance.fit_percent\" is not an array");
  for (std::size_t i = 0; i < files.size(); ++i) {
    out.files.push_back(text(files[i], where, "provenance.files[" + std::to_string(i) + "]"));
  }
  for (std::size_t i = 0; i < fit.size(); ++i) {
    out.fit_percent.push_back(
        number(fit[i], where, "provenance.fit_percent[" + std::to_string(i) + "]"));
  }
  return out;
}

ENDOHAPTICS_DECL ModelFile joint_model_from_json(const json& j, const std::string& kind,
                                                 double sample_time, std::vector<SignalInfo> inputs,
                                                 std::vector<SignalInfo> outputs,
                                                 const std::string& where) {
  for (const char* linear :
       {"states", "A", "B", "C", "D", "x0", "input_nonlinearity", "output_nonlinearity",
        "free_motion_threshold", "current_play", "current_play_slide", "current_play_viscous"}) {
    if (j.contains(linear)) {
      fail(where + ": kind \"" + kind + "\" has no field \"" + linear +
           "\" (its parameters are in \"parameters\")");
    }
  }
  // 3 inputs only for an observer that refers its current to the command (validate() checks that
  // against its current_reference below).
  const std::size_t most = kind == "stall_hold" ? 2 : 3;
  if (inputs.size() < 2 || inputs.size() > most || outputs.size() != 1) {
    fail(where + ": kind \"" + kind + "\" needs 2 inputs (current, velocity" +
         (most == 3 ? std::string("; 3 with the current command") : std::string()) +
         ") and 1 output, got " + std::to_string(inputs.size()) + " and " +
         std::to_string(outputs.size()));
  }
  ModelFile m{.state_space = with_context(where,
                                          [&] {
                                            return joint_model_placeholder(
                                                static_cast<Eigen::Index>(inputs.size()),
                                                sample_time);
                                          }),
              .inputs = std::move(inputs),
              .outputs = std::move(outputs)};
  const json& params = field(j, "parameters", where);
  const std::string what = "for kind \"" + kind + "\"";
  // The alternative whose kind is named: its type's field list reads the object.
  [&]<std::size_t... I>(std::index_sequence<I...>) {
    (
        [&] {
          using P = std::variant_alternative_t<I + 1, JointModelParameters>;
          if (kind == to_string(joint_model_kind<P>())) {
            P p;
            p.sample_time = sample_time;
            parameters_from_json(params, p, where, "parameters", what);
            m.parameters = p;
          }
        }(),
        ...);
  }
  (std::make_index_sequence<std::variant_size_v<JointModelParameters> - 1>{});
  if (const auto it = j.find("current_reference"); it != j.end()) {
    CurrentReference r;
    parameters_from_json(*it, r, where, "current_reference");
    m.current_reference = r;
  }
  m.provenance = provenance_from_json(j, where);
  validate(m, where);
  return m;
}

ENDOHAPTICS_DECL void migrate(json& j, const std::string& where) {
  const auto kind = j.find("kind");
  const auto params = j.find("parameters");
  const bool observer = kind != j.end() && kind->is_string() &&
                        (*kind == "push_load_observer" || *kind == "bidirectional_load_observer");
  if (observer && params != j.end() && params->is_object()) {
    json& p = *params;
    if (*kind == "push_load_observer") {
      // The back-driven map came later: a file without it has none (c_b = 0), all four or none.
      const char* back[] = {"back_current_per_load", "back_current_offset",
                            "back_current_per_velocity", "back_variance"};
      std::size_t present = 0;
      for (const char* name : back) present += p.contains(name) ? 1U : 0U;
      if (present != 0 && present != std::size(back)) {
        fail(where +
             ": parameters: back_current_per_load, back_current_offset, "
             "back_current_per_velocity and back_variance go together (all four or none)");
      }
      if (present == 0) {
        const estimation::PushLoadObserverParameters<double> none;
        p["back_current_per_load"] = 0.0;
        p["back_current_offset"] = none.back_current_offset;
        p["back_current_per_velocity"] = none.back_current_per_velocity;
        p["back_variance"] = none.back_variance;
      }
      if (!p.contains("load_per_angle")) p["load_per_angle"] = 0.0;
    }
    if (p.contains("command_gain") != p.contains("reference_offset")) {
      fail(where + ": parameters: command_gain and reference_offset go together (both or none)");
    }
    if (p.contains("command_gain")) {
      const double gain = number(p["command_gain"], where, "parameters.command_gain");
      const double offset = number(p["reference_offset"], where, "parameters.reference_offset");
      // Without a reference its offset has no meaning: 0.
      if (gain == 0 && offset != 0) {
        fail(where +
             ": field \"parameters.reference_offset\" must be 0 when command_gain is 0, "
             "got " +
             format_number(offset));
      }
      if (gain != 0) {
        j["current_reference"] = {{"command_gain", p["command_gain"]},
                                  {"reference_offset", p["reference_offset"]}};
      }
      p.erase("command_gain");
      p.erase("reference_offset");
    }
  }
  j["version"] = 2;
}

ENDOHAPTICS_DECL json map_to_json(const StaticMap& m) {
  json j{{"type", model::to_string(m.kind)}};
  if (m.kind != StaticMapKind::none) {
    j["lower"] = m.lower;
    j["upper"] = m.upper;
  }
  return j;
}

ENDOHAPTICS_DECL std::vector<StaticMap> maps_from_json(const json& object, const char* key,
                                                       const std::string& where) {
  const json& value = field(object, key, where);
  if (!value.is_array()) fail(where + ": field \"" + key + "\" is not an array");
  std::vector<StaticMap> out;
  for (std::size_t i = 0; i < value.size(); ++i) {
    const std::string name = std::string(key) + "[" + std::to_string(i) + "]";
    const std::string type =
        text(field(value[i], "type", where + ": " + name), where, name + ".type");
    const std::optional<StaticMapKind> kind = model::static_map_kind_from_string(type);
    if (!kind) {
      fail(where + ": field \"" + name + ".type\" is \"" + type +
           "\", expected none, deadzone or saturation");
    }
    StaticMap m{*kind, 0.0, 0.0};
    if (m.kind != StaticMapKind::none) {
      m.lower = number(field(value[i], "lower", where + ": " + name), where, name + ".lower");
      m.upper = number(field(value[i], "upper", where + ": " + name), where, name + ".upper");
    }
    out.push_back(m);
  }
  return out;
}
}  // namespace detail::model_file
}  // namespace endohaptics::files

namespace endohaptics::files {

ENDOHAPTICS_DECL std::string utc_date_today() {
  const std::time_t now = std::chrono::system_clock::to_time_t(std::chrono::system_clock::now());
  std::tm utc{};
  gmtime_r(&now, &utc);
  char buffer[16];
  std::strftime(buffer, sizeof(buffer), "%Y-%m-%d", &utc);
  return buffer;
}

ENDOHAPTICS_DECL nlohmann::json to_json(const ModelFile& m) {
  namespace mf = detail::model_file;
  mf::validate(m, "to_json");
  nlohmann::json j;
  j["format"] = "endohaptics-model";
  j["version"] = ModelFile::format_version;
  j["kind"] = std::string(to_string(m.kind()));
  const model::DynamicStateSpace<>& ss = m.state_space;
  j["sample_time_s"] = ss.sample_time();
  if (!m.is_joint_model()) j["states"] = ss.state_size();
  for (const char* key : {"inputs", "outputs"}) {
    nlohmann::json signals = nlohmann::json::array();
    for (const SignalInfo& s : std::string_view(key) == "inputs" ? m.inputs : m.outputs) {
      signals.push_back({{"name", s.name}, {"unit", s.unit}});
    }
    j[key] = std::move(signals);
  }
  std::visit(
      [&](const auto& p) {
        if constexpr (!std::is_same_v<std::decay_t<decltype(p)>, std::monostate>) {
          j["parameters"] = parameters_to_json(p);
        }
      },
      m.parameters);
  if (m.current_reference) j["current_reference"] = parameters_to_json(*m.current_reference);
  if (!m.is_joint_model()) mf::add_linear_block(j, m);
  const ModelProvenance& p = m.provenance;
  j["provenance"] = {{"method", p.method},
                     {"order", p.order},
                     {"block_rows", p.block_rows},
                     {"files", p.files},
                     {"fit_percent", p.fit_percent},
                     {"date", p.date},
                     {"notes", p.notes}};
  return j;
}

ENDOHAPTICS_DECL ModelFile model_from_json(const nlohmann::json& file, const std::string& source) {
  namespace mf = detail::model_file;
  const std::string where = "model file " + source;
  if (!file.is_object()) mf::fail(where + ": not a JSON object");
  const std::string format = mf::text(mf::field(file, "format", where), where, "format");
  if (format != "endohaptics-model") {
    mf::fail(where + ": field \"format\" is \"" + format + "\", expected \"endohaptics-model\"");
  }
  const int version = mf::integer(mf::field(file, "version", where), where, "version");
  if (version != 1 && version != ModelFile::format_version) {
    mf::fail(where + ": field \"version\" is " + std::to_string(version) + ", expected 1 or " +
             std::to_string(ModelFile::format_version));
  }
  // An older version is read as the current one after its migration (a copy: `file` is the
  // caller's).
  nlohmann::json migrated;
  if (version != ModelFile::format_version) {
    migrated = file;
    mf::migrate(migrated, where);
  }
  const nlohmann::json& j = version != ModelFile::format_version ? migrated : file;
  const std::string kind = mf::text(mf::field(j, "kind", where), where, "kind");
  const bool joint =
      kind == "stall_hold" || kind == "push_load_observer" || kind == "bidirectional_load_observer";
  if (kind != "state_space" && kind != "hammerstein_wiener" && !joint) {
    mf::fail(where + ": field \"kind\" is \"" + kind +
             "\", expected \"state_space\", \"hammerstein_wiener\", \"stall_hold\", "
             "\"push_load_observer\" or \"bidirectional_load_observer\"");
  }
  const double sample_time =
      mf::number(mf::field(j, "sample_time_s", where), where, "sample_time_s");
  if (!std::isfinite(sample_time) || !(sample_time > 0.0)) {
    mf::fail(where + ": field \"sample_time_s\" must be finite and > 0, got " +
             mf::format_number(sample_time));
  }
  std::vector<SignalInfo> inputs = mf::signals_from_json(j, "inputs", where);
  std::vector<SignalInfo> outputs = mf::signals_from_json(j, "outputs", where);
  if (outputs.empty()) mf::fail(where + ": field \"outputs\" must name at least one output");
  if (joint) {
    return mf::joint_model_from_json(j, kind, sample_time, std::move(inputs), std::move(outputs),
                                     where);
  }
  const int n =
      mf::integer(mf::field(j, "states", where), where, "states", 1, ModelFile::max_states);
  const auto nu = static_cast<Eigen::Index>(inputs.size());
  const auto ny = static_cast<Eigen::Index>(outputs.size());
  const Eigen::MatrixXd A = mf::matrix_from_json(j, "A", n, n, "states", "states", where);
  const Eigen::MatrixXd B = mf::matrix_from_json(j, "B", n, nu, "states", "inputs", where);
  const Eigen::MatrixXd C = mf::matrix_from_json(j, "C", ny, n, "outputs", "states", where);
  const Eigen::MatrixXd D = mf::matrix_from_json(j, "D", ny, nu, "outputs", "inputs", where);
  const auto& x0 = mf::field(j, "x0", where);
  if (!x0.is_array() || static_cast<int>(x0.size()) != n) {
    mf::fail(where + ": field \"x0\" must be an array of " + std::to_string(n) +
             " numbers (states), got " + detail::json_text::show(x0));
  }
  Eigen::VectorXd state(n);
  for (int i = 0; i < n; ++i) {
    state[i] = mf::number(x0[static_cast<std::size_t>(i)], where, "x0[" + std::to_string(i) + "]");
  }
  // Sizes and values are checked above, field by field; the StateSpace checks them again.
  ModelFile m{.state_space = mf::with_context(
                  where, [&] { return model::DynamicStateSpace<>(A, B, C, D, sample_time); }),
              .inputs = std::move(inputs),
              .outputs = std::move(outputs)};
  m.state_space.reset(state);
  if (kind == "hammerstein_wiener") {
    m.input_nonlinearity = mf::maps_from_json(j, "input_nonlinearity", where);
    m.output_nonlinearity = mf::maps_from_json(j, "output_nonlinearity", where);
    if (m.input_nonlinearity.empty() && m.output_nonlinearity.empty()) {
      mf::fail(where +
               ": kind \"hammerstein_wiener\" needs input_nonlinearity or "
               "output_nonlinearity entries");
    }
  }
  if (j.contains("free_motion_threshold")) {  // its range: validate, below
    m.free_motion_threshold =
        mf::number(j["free_motion_threshold"], where, "free_motion_threshold");
  }
  if (j.contains("current_play")) {  // its range: validate, below
    m.current_play = mf::number(j["current_play"], where, "current_play");
  }
  if (j.contains("current_play_slide")) {  // its range: validate, below
    m.current_play_slide = mf::number(j["current_play_slide"], where, "current_play_slide");
  }
  if (j.contains("current_play_viscous")) {  // its range: validate, below
    m.current_play_viscous = mf::number(j["current_play_viscous"], where, "current_play_viscous");
  }
  m.provenance = mf::provenance_from_json(j, where);
  mf::validate(m, where);
  return m;
}

ENDOHAPTICS_DECL ModelFile make_joint_model_file(JointModelParameters parameters,
                                                 std::vector<SignalInfo> inputs,
                                                 std::vector<SignalInfo> outputs,
                                                 ModelProvenance provenance,
                                                 std::optional<CurrentReference> reference) {
  namespace mf = detail::model_file;
  const char* where = "make_joint_model_file";
  if (parameters.index() == 0) mf::fail(std::string(where) + ": no joint model's parameters");
  const double sample_time = std::visit(
      [](const auto& p) -> double {
        if constexpr (std::is_same_v<std::decay_t<decltype(p)>, std::monostate>) {
          return 0.0;
        } else {
          return p.sample_time;
        }
      },
      parameters);
  ModelFile f{.state_space = mf::with_context(where,
                                              [&] {
                                                return mf::joint_model_placeholder(
                                                    static_cast<Eigen::Index>(inputs.size()),
                                                    sample_time);
                                              }),
              .inputs = std::move(inputs),
              .outputs = std::move(outputs),
              .provenance = std::move(provenance),
              .parameters = std::move(parameters),
              .current_reference = std::move(reference)};
  if (f.provenance.date.empty()) f.provenance.date = utc_date_today();
  mf::validate(f, where);
  return f;
}

ENDOHAPTICS_DECL void save_model(const std::filesystem::path& path, const ModelFile& model) {
  const nlohmann::json j = to_json(model);
  std::ofstream out(path);
  if (!out) detail::model_file::fail("save_model: cannot open " + path.string() + " for writing");
  out << j.dump(2) << '\n';
  out.close();  // flushes: a full disk shows here, not in the destructor
  if (!out) detail::model_file::fail("save_model: writing " + path.string() + " failed");
}

ENDOHAPTICS_DECL ModelFile load_model(const std::filesystem::path& path) {
  namespace jt = detail::json_text;
  const std::string text = jt::read_bounded(path, model_file_max_bytes, "model file");
  const nlohmann::json j = jt::parse_strict(
      text, "model file " + path.string(),
      {.max_depth = model_file_max_depth, .needed = "a model file needs 4", .comments = false});
  return model_from_json(j, path.string());
}

}  // namespace endohaptics::files
