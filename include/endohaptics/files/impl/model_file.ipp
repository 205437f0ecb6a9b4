//! @file
//! Function bodies of files/model_file.hpp: included at its end (header-only, the default), or
//! compiled once with ENDOHAPTICS_SEPARATE_COMPILATION (core/separate_compilation.hpp).
#pragma once

#include "endohaptics/files/model_file.hpp"

namespace endohaptics::files {
namespace detail::model_file {

ENDOHAPTICS_DECL void require_parameter(bool ok, const std::string& where, const char* name,
                                        double value, const char* rule) {
  if (!ok) {
    fail(where + ": field \"parameters." + name + "\" must be " + rule + ", got " +
         format_number(value));
  }
}

constexpr double max_parameter = ModelFile::max_parameter;

ENDOHAPTICS_DECL void validate_settings(const StallHoldSettings& p, const std::string& where) {
  const auto non_negative = [&](const char* name, double v, const char* rule) {
    require_parameter(v >= 0.0 && v <= max_parameter, where, name, v, rule);  // false for NaN
  };
  non_negative("current_deadzone", p.current_deadzone, "in [0, 1e6] A");
  non_negative("velocity_threshold", p.velocity_threshold, "in [0, 1e6] rad/s");
  non_negative("velocity_time_constant", p.velocity_time_constant, "in [0, 1e6] s");
  non_negative("output_time_constant", p.output_time_constant, "in [0, 1e6] s");
  require_parameter(std::fabs(p.gain) <= max_parameter, where, "gain", p.gain, "in [-1e6, 1e6]");
  if (p.side != "both" && p.side != "positive" && p.side != "negative") {
    fail(where + ": field \"parameters.side\" is \"" + p.side +
         "\", expected \"both\", \"positive\" or \"negative\"");
  }
}

ENDOHAPTICS_DECL void validate_settings(const PushLoadObserverSettings& p, double sample_time,
                                        const std::string& where) {
  const double nyquist = 0.5 / sample_time;
  require_parameter(p.current_cutoff > 0 && p.current_cutoff < nyquist, where, "current_cutoff",
                    p.current_cutoff, "in (0, Nyquist = 0.5 / sample_time_s) Hz");
  require_parameter(p.velocity_cutoff > 0 && p.velocity_cutoff < nyquist, where, "velocity_cutoff",
                    p.velocity_cutoff, "in (0, Nyquist = 0.5 / sample_time_s) Hz");
  require_parameter(p.direction_scale > 0 && p.direction_scale <= max_parameter, where,
                    "direction_scale", p.direction_scale, "in (0, 1e6] rad");
  require_parameter(p.velocity_threshold >= 0 && p.velocity_threshold <= max_parameter, where,
                    "velocity_threshold", p.velocity_threshold, "in [0, 1e6] rad/s");
  require_parameter(p.direction_threshold > 0 && p.direction_threshold <= 1, where,
                    "direction_threshold", p.direction_threshold, "in (0, 1]");
  require_parameter(p.push_sign == 1 || p.push_sign == -1, where, "push_sign", p.push_sign,
                    "+1 or -1");
  require_parameter(std::fabs(p.current_per_load) >= ModelFile::min_current_per_load &&
                        std::fabs(p.current_per_load) <= max_parameter,
                    where, "current_per_load", p.current_per_load, "of magnitude in [1e-9, 1e6]");
  const std::pair<const char*, double> finite[] = {
      {"current_offset", p.current_offset},
      {"current_per_velocity", p.current_per_velocity},
      {"initial_load", p.initial_load},
      {"output_offset", p.output_offset},
      {"output_slope", p.output_slope},
      {"back_current_offset", p.back_current_offset},
      {"back_current_per_velocity", p.back_current_per_velocity},
      {"load_per_angle", p.load_per_angle},
      {"reference_offset", p.reference_offset}};
  for (const auto& [name, v] : finite)
    require_parameter(std::fabs(v) <= max_parameter, where, name, v, "in [-1e6, 1e6]");
  require_parameter(p.measurement_variance > 0 && p.measurement_variance <= max_parameter, where,
                    "measurement_variance", p.measurement_variance, "in (0, 1e6]");
  require_parameter(p.process_variance >= 0 && p.process_variance <= max_parameter, where,
                    "process_variance", p.process_variance, "in [0, 1e6]");
  require_parameter(p.initial_variance >= 0 && p.initial_variance <= max_parameter, where,
                    "initial_variance", p.initial_variance, "in [0, 1e6]");
  require_parameter(p.back_current_per_load == 0 ||
                        (std::fabs(p.back_current_per_load) >= ModelFile::min_current_per_load &&
                         std::fabs(p.back_current_per_load) <= max_parameter),
                    where, "back_current_per_load", p.back_current_per_load,
                    "0 or of magnitude in [1e-9, 1e6]");
  require_parameter(p.back_variance > 0 && p.back_variance <= max_parameter, where, "back_variance",
                    p.back_variance, "in (0, 1e6]");
  require_parameter(
      p.command_gain == 0 || (std::fabs(p.command_gain) >= ModelFile::min_current_per_load &&
                              std::fabs(p.command_gain) <= max_parameter),
      where, "command_gain", p.command_gain, "0 or of magnitude in [1e-9, 1e6]");
  // Without a reference its offset has no meaning (and to_json would drop it): 0.
  require_parameter(p.command_gain != 0 || p.reference_offset == 0, where, "reference_offset",
                    p.reference_offset, "0 when command_gain is 0");
}

// The scalar fields of BidirectionalObserverSettings by their file names (one list for reading,
// writing and checking), the reference pair apart (optional, both or none).
using BidirectionalScalar = double BidirectionalObserverSettings::*;
inline constexpr std::pair<const char*, BidirectionalScalar> bidirectional_scalars[] = {
    {"current_cutoff", &BidirectionalObserverSettings::current_cutoff},
    {"velocity_cutoff", &BidirectionalObserverSettings::velocity_cutoff},
    {"direction_scale", &BidirectionalObserverSettings::direction_scale},
    {"velocity_threshold", &BidirectionalObserverSettings::velocity_threshold},
    {"direction_threshold", &BidirectionalObserverSettings::direction_threshold},
    {"start_travel", &BidirectionalObserverSettings::start_travel},
    {"forward_gain", &BidirectionalObserverSettings::forward_gain},
    {"forward_gain_stroke", &BidirectionalObserverSettings::forward_gain_stroke},
    {"forward_offset", &BidirectionalObserverSettings::forward_offset},
    {"forward_offset_stroke", &BidirectionalObserverSettings::forward_offset_stroke},
    {"backward_gain", &BidirectionalObserverSettings::backward_gain},
    {"backward_gain_stroke", &BidirectionalObserverSettings::backward_gain_stroke},
    {"backward_offset", &BidirectionalObserverSettings::backward_offset},
    {"backward_offset_stroke", &BidirectionalObserverSettings::backward_offset_stroke},
    {"forward_variance", &BidirectionalObserverSettings::forward_variance},
    {"backward_variance", &BidirectionalObserverSettings::backward_variance},
    {"load_process_variance", &BidirectionalObserverSettings::load_process_variance},
    {"friction_variance", &BidirectionalObserverSettings::friction_variance},
    {"friction_process_variance", &BidirectionalObserverSettings::friction_process_variance},
    {"initial_load", &BidirectionalObserverSettings::initial_load},
    {"initial_variance", &BidirectionalObserverSettings::initial_variance},
    {"output_offset", &BidirectionalObserverSettings::output_offset}};
using BidirectionalArray = BidirectionalObserverSettings::Stops BidirectionalObserverSettings::*;
inline constexpr std::pair<const char*, BidirectionalArray> bidirectional_arrays[] = {
    {"stop_thresholds", &BidirectionalObserverSettings::stop_thresholds},
    {"output_shape", &BidirectionalObserverSettings::output_shape},
    {"output_shape_per_load", &BidirectionalObserverSettings::output_shape_per_load}};

ENDOHAPTICS_DECL void validate_settings(const BidirectionalObserverSettings& p, double sample_time,
                                        const std::string& where) {
  const double nyquist = 0.5 / sample_time;
  const double max = max_parameter;
  // Every number within the joint-model bound first (comparisons fail for NaN).
  for (const auto& [name, member] : bidirectional_scalars) {
    require_parameter(std::fabs(p.*member) <= max, where, name, p.*member, "in [-1e6, 1e6]");
  }
  for (const auto& [name, member] : bidirectional_arrays) {
    for (std::size_t j = 0; j < (p.*member).size(); ++j) {
      const std::string field = std::string(name) + "[" + std::to_string(j) + "]";
      require_parameter(std::fabs((p.*member)[j]) <= max, where, field.c_str(), (p.*member)[j],
                        "in [-1e6, 1e6]");
    }
  }
  require_parameter(p.current_cutoff > 0 && p.current_cutoff < nyquist, where, "current_cutoff",
                    p.current_cutoff, "in (0, Nyquist = 0.5 / sample_time_s) Hz");
  require_parameter(p.velocity_cutoff > 0 && p.velocity_cutoff < nyquist, where, "velocity_cutoff",
                    p.velocity_cutoff, "in (0, Nyquist = 0.5 / sample_time_s) Hz");
  require_parameter(p.direction_scale > 0, where, "direction_scale", p.direction_scale, "> 0 rad");
  require_parameter(p.velocity_threshold >= 0, where, "velocity_threshold", p.velocity_threshold,
                    ">= 0 rad/s");
  require_parameter(p.direction_threshold > 0 && p.direction_threshold <= 1, where,
                    "direction_threshold", p.direction_threshold, "in (0, 1]");
  for (std::size_t j = 0; j < p.stop_thresholds.size(); ++j) {
    const std::string field = "stop_thresholds[" + std::to_string(j) + "]";
    require_parameter(
        p.stop_thresholds[j] > 0 && (j == 0 || p.stop_thresholds[j] > p.stop_thresholds[j - 1]),
        where, field.c_str(), p.stop_thresholds[j], "> 0 and above the threshold before it");
  }
  require_parameter(p.start_travel >= 0, where, "start_travel", p.start_travel, ">= 0 rad");
  // The rules of estimation::BidirectionalLoadObserverParameters::validate().
  const auto map = [&](const char* gain_name, double g, double stroke, const char* stroke_name) {
    require_parameter(std::fabs(g) >= ModelFile::min_current_per_load, where, gain_name, g,
                      "of magnitude in [1e-9, 1e6]");
    require_parameter(std::fabs(stroke) <= 0.9 * std::fabs(g), where, stroke_name, stroke,
                      "at most 0.9 times the gain's magnitude (the gain keeps its sign and a "
                      "tenth of its size along the stroke)");
  };
  map("forward_gain", p.forward_gain, p.forward_gain_stroke, "forward_gain_stroke");
  map("backward_gain", p.backward_gain, p.backward_gain_stroke, "backward_gain_stroke");
  require_parameter(p.forward_gain / p.backward_gain > 0 && p.forward_gain / p.backward_gain <= max,
                    where, "backward_gain", p.backward_gain,
                    "of forward_gain's sign and at least 1e-6 times its magnitude (the current "
                    "grows with the load both ways)");
  require_parameter(p.forward_variance >= 1e-12, where, "forward_variance", p.forward_variance,
                    "in [1e-12, 1e6]");
  require_parameter(p.backward_variance >= 1e-12, where, "backward_variance", p.backward_variance,
                    "in [1e-12, 1e6]");
  const std::pair<const char*, double> non_negative[] = {
      {"load_process_variance", p.load_process_variance},
      {"friction_variance", p.friction_variance},
      {"friction_process_variance", p.friction_process_variance},
      {"initial_variance", p.initial_variance}};
  for (const auto& [name, v] : non_negative) {
    require_parameter(v >= 0, where, name, v, "in [0, 1e6]");
  }
  require_parameter(
      p.command_gain == 0 || (std::fabs(p.command_gain) >= ModelFile::min_current_per_load &&
                              std::fabs(p.command_gain) <= max),
      where, "command_gain", p.command_gain, "0 or of magnitude in [1e-9, 1e6]");
  require_parameter(std::fabs(p.reference_offset) <= max, where, "reference_offset",
                    p.reference_offset, "in [-1e6, 1e6]");
  require_parameter(p.command_gain != 0 || p.reference_offset == 0, where, "reference_offset",
                    p.reference_offset, "0 when command_gain is 0");
}

// The inputs a joint model takes: (current, velocity), and for an observer that refers its
// current to the command, that command third.
inline std::size_t joint_model_inputs(const ModelFile& m) {
  return m.command_reference().first != 0 ? 3 : 2;
}

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
  if (int(m.stall_hold.has_value()) + int(m.push_load_observer.has_value()) +
          int(m.bidirectional_load_observer.has_value()) >
      1) {
    fail(where +
         ": a model file holds one joint model, not the parameters of several (stall_hold, "
         "push_load_observer, bidirectional_load_observer)");
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
    if (ss.state_size() != 1 || ss.input_size() != static_cast<Eigen::Index>(nu) ||
        ss.output_size() != 1 || !ss.A().isZero(0.0) || !ss.B().isZero(0.0) ||
        !ss.C().isZero(0.0) || !ss.D().isZero(0.0) || !ss.state().isZero(0.0)) {
      fail(where + ": kind \"" + kind +
           "\": the linear block must be the placeholder (1 state, one column per input, 1 "
           "output, all zero)");
    }
    if (m.stall_hold) validate_settings(*m.stall_hold, where);
    if (m.push_load_observer) validate_settings(*m.push_load_observer, ss.sample_time(), where);
    if (m.bidirectional_load_observer) {
      validate_settings(*m.bidirectional_load_observer, ss.sample_time(), where);
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
       {"states", "A", "B", "C", "D", "x0", "input_nonlinearity", "output_nonlinearity"}) {
    if (j.contains(linear)) {
      fail(where + ": kind \"" + kind + "\" has no field \"" + linear +
           "\" (its parameters are in \"parameters\")");
    }
  }
  // 3 inputs only for an observer that refers its current to the command (validate() checks that
  // against its parameters below).
  const std::size_t most = kind == "stall_hold" ? 2 : 3;
  if (inputs.size() < 2 || inputs.size() > most || outputs.size() != 1) {
    fail(where + ": kind \"" + kind + "\" needs 2 inputs (current, velocity" +
         (most == 3 ? std::string("; 3 with the current command") : std::string()) +
         ") and 1 output, got " + std::to_string(inputs.size()) + " and " +
         std::to_string(outputs.size()));
  }
  const json& params = field(j, "parameters", where);
  if (!params.is_object()) fail(where + ": field \"parameters\" is not an object");
  std::vector<std::string> known;
  const auto get = [&](const char* name, double& out) {
    known.emplace_back(name);
    out = number(field(params, name, where + ": parameters"), where,
                 std::string("parameters.") + name);
  };
  ModelFile m{.state_space = with_context(where,
                                          [&] {
                                            return joint_model_placeholder(
                                                static_cast<Eigen::Index>(inputs.size()),
                                                sample_time);
                                          }),
              .inputs = std::move(inputs),
              .outputs = std::move(outputs)};
  if (kind == "stall_hold") {
    StallHoldSettings p;
    get("current_deadzone", p.current_deadzone);
    get("velocity_threshold", p.velocity_threshold);
    get("velocity_time_constant", p.velocity_time_constant);
    get("output_time_constant", p.output_time_constant);
    get("gain", p.gain);
    known.emplace_back("side");
    p.side = text(field(params, "side", where + ": parameters"), where, "parameters.side");
    m.stall_hold = p;
  } else if (kind == "bidirectional_load_observer") {
    BidirectionalObserverSettings p;
    for (const auto& [name, member] : bidirectional_scalars) get(name, p.*member);
    for (const auto& [name, member] : bidirectional_arrays) {
      known.emplace_back(name);
      const json& array = field(params, name, where + ": parameters");
      if (!array.is_array() || array.size() != (p.*member).size()) {
        fail(where + ": field \"parameters." + name + "\" must be an array of " +
             std::to_string((p.*member).size()) + " numbers (one per stop operator), got " +
             detail::json_text::show(array));
      }
      for (std::size_t i = 0; i < array.size(); ++i) {
        (p.*member)[i] = number(array[i], where,
                                std::string("parameters.") + name + "[" + std::to_string(i) + "]");
      }
    }
    if (params.contains("command_gain") != params.contains("reference_offset")) {
      fail(where + ": parameters: command_gain and reference_offset go together (both or none)");
    }
    if (params.contains("command_gain")) {
      get("command_gain", p.command_gain);
      get("reference_offset", p.reference_offset);
    } else {
      known.emplace_back("command_gain");
      known.emplace_back("reference_offset");
    }
    m.bidirectional_load_observer = p;
  } else {
    PushLoadObserverSettings p;
    get("current_cutoff", p.current_cutoff);
    get("velocity_cutoff", p.velocity_cutoff);
    get("direction_scale", p.direction_scale);
    get("velocity_threshold", p.velocity_threshold);
    get("direction_threshold", p.direction_threshold);
    get("push_sign", p.push_sign);
    get("current_per_load", p.current_per_load);
    get("current_offset", p.current_offset);
    get("current_per_velocity", p.current_per_velocity);
    get("measurement_variance", p.measurement_variance);
    get("process_variance", p.process_variance);
    get("initial_load", p.initial_load);
    get("initial_variance", p.initial_variance);
    get("output_offset", p.output_offset);
    get("output_slope", p.output_slope);
    // The back-driven map came later: a file without it has none (c_b = 0), all four or none.
    const char* back[] = {"back_current_per_load", "back_current_offset",
                          "back_current_per_velocity", "back_variance"};
    std::size_t present = 0;
    for (const char* name : back) present += params.contains(name) ? 1U : 0U;
    if (present != 0 && present != std::size(back)) {
      fail(where +
           ": parameters: back_current_per_load, back_current_offset, "
           "back_current_per_velocity and back_variance go together (all four or none)");
    }
    if (present != 0) {
      get("back_current_per_load", p.back_current_per_load);
      get("back_current_offset", p.back_current_offset);
      get("back_current_per_velocity", p.back_current_per_velocity);
      get("back_variance", p.back_variance);
    } else {
      for (const char* name : back) known.emplace_back(name);
    }
    // Later still, each optional (absent: 0, none): the stiffness, and the current's offset
    // reference to the command (both of its fields or none).
    if (params.contains("load_per_angle")) {
      get("load_per_angle", p.load_per_angle);
    } else {
      known.emplace_back("load_per_angle");
    }
    if (params.contains("command_gain") != params.contains("reference_offset")) {
      fail(where + ": parameters: command_gain and reference_offset go together (both or none)");
    }
    if (params.contains("command_gain")) {
      get("command_gain", p.command_gain);
      get("reference_offset", p.reference_offset);
    } else {
      known.emplace_back("command_gain");
      known.emplace_back("reference_offset");
    }
    m.push_load_observer = p;
  }
  for (const auto& [key, value] : params.items()) {
    if (std::find(known.begin(), known.end(), key) == known.end()) {
      std::string all;
      for (const auto& k : known) all += (all.empty() ? "" : ", ") + k;
      fail(where + ": unknown field \"parameters." + key + "\" for kind \"" + kind +
           "\" (known: " + all + ")");
    }
  }
  m.provenance = provenance_from_json(j, where);
  validate(m, where);
  return m;
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
  if (m.stall_hold) {
    const StallHoldSettings& p = *m.stall_hold;
    j["parameters"] = {{"current_deadzone", p.current_deadzone},
                       {"velocity_threshold", p.velocity_threshold},
                       {"velocity_time_constant", p.velocity_time_constant},
                       {"output_time_constant", p.output_time_constant},
                       {"gain", p.gain},
                       {"side", p.side}};
  }
  if (m.push_load_observer) {
    const PushLoadObserverSettings& p = *m.push_load_observer;
    j["parameters"] = {{"current_cutoff", p.current_cutoff},
                       {"velocity_cutoff", p.velocity_cutoff},
                       {"direction_scale", p.direction_scale},
                       {"velocity_threshold", p.velocity_threshold},
                       {"direction_threshold", p.direction_threshold},
                       {"push_sign", p.push_sign},
                       {"current_per_load", p.current_per_load},
                       {"current_offset", p.current_offset},
                       {"current_per_velocity", p.current_per_velocity},
                       {"measurement_variance", p.measurement_variance},
                       {"process_variance", p.process_variance},
                       {"initial_load", p.initial_load},
                       {"initial_variance", p.initial_variance},
                       {"output_offset", p.output_offset},
                       {"output_slope", p.output_slope},
                       {"back_current_per_load", p.back_current_per_load},
                       {"back_current_offset", p.back_current_offset},
                       {"back_current_per_velocity", p.back_current_per_velocity},
                       {"back_variance", p.back_variance},
                       {"load_per_angle", p.load_per_angle}};
    if (p.command_gain != 0) {
      j["parameters"]["command_gain"] = p.command_gain;
      j["parameters"]["reference_offset"] = p.reference_offset;
    }
  }
  if (m.bidirectional_load_observer) {
    const BidirectionalObserverSettings& p = *m.bidirectional_load_observer;
    nlohmann::json& params = j["parameters"] = nlohmann::json::object();
    for (const auto& [name, member] : mf::bidirectional_scalars) params[name] = p.*member;
    for (const auto& [name, member] : mf::bidirectional_arrays) params[name] = p.*member;
    if (p.command_gain != 0) {
      params["command_gain"] = p.command_gain;
      params["reference_offset"] = p.reference_offset;
    }
  }
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

ENDOHAPTICS_DECL ModelFile model_from_json(const nlohmann::json& j, const std::string& source) {
  namespace mf = detail::model_file;
  const std::string where = "model file " + source;
  if (!j.is_object()) mf::fail(where + ": not a JSON object");
  const std::string format = mf::text(mf::field(j, "format", where), where, "format");
  if (format != "endohaptics-model") {
    mf::fail(where + ": field \"format\" is \"" + format + "\", expected \"endohaptics-model\"");
  }
  const int version = mf::integer(mf::field(j, "version", where), where, "version");
  if (version != ModelFile::format_version) {
    mf::fail(where + ": field \"version\" is " + std::to_string(version) + ", expected " +
             std::to_string(ModelFile::format_version));
  }
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
  m.provenance = mf::provenance_from_json(j, where);
  mf::validate(m, where);
  return m;
}

ENDOHAPTICS_DECL ModelFile make_stall_hold_file(const StallHoldSettings& settings,
                                                double sample_time, std::vector<SignalInfo> inputs,
                                                std::vector<SignalInfo> outputs,
                                                ModelProvenance provenance) {
  namespace mf = detail::model_file;
  ModelFile f{
      .state_space = mf::with_context("make_stall_hold_file",
                                      [&] { return mf::joint_model_placeholder(2, sample_time); }),
      .inputs = std::move(inputs),
      .outputs = std::move(outputs),
      .provenance = std::move(provenance),
      .stall_hold = settings};
  if (f.provenance.date.empty()) f.provenance.date = utc_date_today();
  mf::validate(f, "make_stall_hold_file");
  return f;
}

ENDOHAPTICS_DECL ModelFile make_push_load_observer_file(const PushLoadObserverSettings& settings,
                                                        double sample_time,
                                                        std::vector<SignalInfo> inputs,
                                                        std::vector<SignalInfo> outputs,
                                                        ModelProvenance provenance) {
  namespace mf = detail::model_file;
  ModelFile f{.state_space = mf::with_context("make_push_load_observer_file",
                                              [&] {
                                                return mf::joint_model_placeholder(
                                                    static_cast<Eigen::Index>(inputs.size()),
                                                    sample_time);
                                              }),
              .inputs = std::move(inputs),
              .outputs = std::move(outputs),
              .provenance = std::move(provenance),
              .push_load_observer = settings};
  if (f.provenance.date.empty()) f.provenance.date = utc_date_today();
  mf::validate(f, "make_push_load_observer_file");
  return f;
}

ENDOHAPTICS_DECL ModelFile make_bidirectional_observer_file(
    const BidirectionalObserverSettings& settings, double sample_time,
    std::vector<SignalInfo> inputs, std::vector<SignalInfo> outputs, ModelProvenance provenance) {
  namespace mf = detail::model_file;
  ModelFile f{.state_space = mf::with_context("make_bidirectional_observer_file",
                                              [&] {
                                                return mf::joint_model_placeholder(
                                                    static_cast<Eigen::Index>(inputs.size()),
                                                    sample_time);
                                              }),
              .inputs = std::move(inputs),
              .outputs = std::move(outputs),
              .provenance = std::move(provenance),
              .bidirectional_load_observer = settings};
  if (f.provenance.date.empty()) f.provenance.date = utc_date_today();
  mf::validate(f, "make_bidirectional_observer_file");
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
