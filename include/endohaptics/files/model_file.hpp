//! @file
//! Identified-model files (JSON, nlohmann::json): a discrete state-space model (eq. 4.2) or a
//! Hammerstein-Wiener model (figure 4.1) with dead-zone/saturation breakpoints, sample time in s,
//! input/output names and units, initial state and provenance (method, order, files, fit, date).
//! Loading validates every field and throws Error naming the file, the field and the value.
//! Format: docs/models/subspace.md, "Model files".
#pragma once

#include <Eigen/Core>
#include <chrono>
#include <cmath>
#include <ctime>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <sstream>
#include <string>
#include <string_view>
#include <type_traits>
#include <vector>

#include "endohaptics/core/error.hpp"
#include "endohaptics/identification/hammerstein_wiener_fit.hpp"
#include "endohaptics/identification/subspace.hpp"
#include "endohaptics/model/hammerstein_wiener.hpp"
#include "endohaptics/model/state_space.hpp"
#include "endohaptics/model/static_nonlinearity.hpp"

namespace endohaptics::files {

//! Name and unit of one input or output signal (e.g. {"current", "A"}).
struct SignalInfo {
  std::string name;  //!< signal name
  std::string unit;  //!< unit symbol ("" for dimensionless)
};

//! Where a model came from.
struct ModelProvenance {
  std::string method;               //!< e.g. "moesp", "n4sid", "cva", "worksheet appendix C"
  int order = 0;                    //!< model order n
  int block_rows = 0;               //!< subspace horizon s (0: not applicable)
  std::vector<std::string> files;   //!< data files it was identified from
  std::vector<double> fit_percent;  //!< NRMSE fit per output, %, on the data named in `notes`
  std::string date;                 //!< ISO 8601 (UTC) date of identification
  std::string notes;                //!< free text
};

//! The content of a model file: dynamic sizes, validated on load and save.
struct ModelFile {
  static constexpr int format_version = 1;  //!< "version" written and accepted
  double sample_time = 0.0;                 //!< s, > 0
  Eigen::MatrixXd A;                        //!< n x n
  Eigen::MatrixXd B;                        //!< n x nu
  Eigen::MatrixXd C;                        //!< ny x n
  Eigen::MatrixXd D;                        //!< ny x nu
  Eigen::VectorXd x0;                       //!< n, initial state (zero when not identified)
  std::vector<SignalInfo> inputs;           //!< nu entries
  std::vector<SignalInfo> outputs;          //!< ny entries
  //! Hammerstein-Wiener maps, nu and ny entries; both empty for a plain state-space model.
  std::vector<identification::StaticMap> input_nonlinearity;
  std::vector<identification::StaticMap> output_nonlinearity;  //!< see input_nonlinearity
  ModelProvenance provenance;                                  //!< where it came from

  //! True when the file describes a Hammerstein-Wiener model ("kind": "hammerstein_wiener").
  [[nodiscard]] bool is_hammerstein_wiener() const noexcept {
    return !input_nonlinearity.empty() || !output_nonlinearity.empty();
  }
};

namespace detail::model_file {

using identification::StaticMap;
using identification::StaticMapKind;
using nlohmann::json;

[[noreturn]] inline void fail(const std::string& message) { ENDOHAPTICS_THROW(Error(message)); }

using endohaptics::detail::format_number;

//! Throws unless sizes agree and every number is finite; `where` prefixes the message.
inline void validate(const ModelFile& m, const std::string& where) {
  const auto n = m.A.rows();
  const auto nu = static_cast<Eigen::Index>(m.inputs.size());
  const auto ny = static_cast<Eigen::Index>(m.outputs.size());
  auto size = [&](const char* field, const Eigen::MatrixXd& M, Eigen::Index rows, Eigen::Index cols,
                  const char* row_name, const char* col_name) {
    if (M.rows() != rows || M.cols() != cols) {
      fail(where + ": field \"" + field + "\" is " + std::to_string(M.rows()) + " x " +
           std::to_string(M.cols()) + ", expected " + std::to_string(rows) + " x " +
           std::to_string(cols) + " (" + row_name + " x " + col_name + ")");
    }
    for (Eigen::Index j = 0; j < M.cols(); ++j) {
      for (Eigen::Index i = 0; i < M.rows(); ++i) {
        if (!std::isfinite(M(i, j))) {
          fail(where + ": field \"" + field + "[" + std::to_string(i) + "][" + std::to_string(j) +
               "]\" is not finite (" + format_number(M(i, j)) + ")");
        }
      }
    }
  };
  if (n < 1) fail(where + ": field \"A\" must have at least one state, got 0");
  if (!std::isfinite(m.sample_time) || !(m.sample_time > 0.0)) {
    fail(where + ": field \"sample_time_s\" must be finite and > 0, got " +
         format_number(m.sample_time));
  }
  if (ny < 1) fail(where + ": field \"outputs\" must name at least one output");
  size("A", m.A, n, n, "states", "states");
  size("B", m.B, n, nu, "states", "inputs");
  size("C", m.C, ny, n, "outputs", "states");
  size("D", m.D, ny, nu, "outputs", "inputs");
  size("x0", m.x0, n, 1, "states", "1");
  auto maps = [&](const char* field, const std::vector<StaticMap>& v, Eigen::Index count,
                  const char* what) {
    if (static_cast<Eigen::Index>(v.size()) != count) {
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

inline json matrix_to_json(const Eigen::MatrixXd& M) {
  json rows = json::array();
  for (Eigen::Index i = 0; i < M.rows(); ++i) {
    json row = json::array();
    for (Eigen::Index j = 0; j < M.cols(); ++j) row.push_back(M(i, j));
    rows.push_back(std::move(row));
  }
  return rows;
}

//! Reads field `key` of `object`; throws naming it when missing.
inline const json& field(const json& object, const char* key, const std::string& where) {
  const auto it = object.find(key);
  if (it == object.end()) fail(where + ": missing field \"" + key + "\"");
  return *it;
}

inline double number(const json& value, const std::string& where, const std::string& name) {
  if (!value.is_number()) {
    fail(where + ": field \"" + name + "\" is not a number (" + value.dump() + ")");
  }
  return value.get<double>();
}

inline std::string text(const json& value, const std::string& where, const std::string& name) {
  if (!value.is_string()) {
    fail(where + ": field \"" + name + "\" is not a string (" + value.dump() + ")");
  }
  return value.get<std::string>();
}

inline int integer(const json& value, const std::string& where, const std::string& name) {
  if (!value.is_number_integer()) {
    fail(where + ": field \"" + name + "\" is not an integer (" + value.dump() + ")");
  }
  return value.get<int>();
}

//! A matrix stored as an array of `rows` rows of `cols` numbers.
inline Eigen::MatrixXd matrix_from_json(const json& object, const char* key, Eigen::Index rows,
                                        Eigen::Index cols, const char* row_name,
                                        const char* col_name, const std::string& where) {
  const json& value = field(object, key, where);
  const std::string name(key);
  if (!value.is_array()) fail(where + ": field \"" + name + "\" is not an array of rows");
  if (static_cast<Eigen::Index>(value.size()) != rows) {
    fail(where + ": field \"" + name + "\" has " + std::to_string(value.size()) +
         " rows, expected " + std::to_string(rows) + " (" + row_name + ")");
  }
  Eigen::MatrixXd M(rows, cols);
  for (Eigen::Index i = 0; i < rows; ++i) {
    const json& row = value[static_cast<std::size_t>(i)];
    const std::string row_field = name + "[" + std::to_string(i) + "]";
    if (!row.is_array() || static_cast<Eigen::Index>(row.size()) != cols) {
      fail(where + ": field \"" + row_field + "\" has " +
           (row.is_array() ? std::to_string(row.size()) : std::string("no")) +
           " columns, expected " + std::to_string(cols) + " (" + col_name + ")");
    }
    for (Eigen::Index j = 0; j < cols; ++j) {
      const std::string entry = row_field + "[" + std::to_string(j) + "]";
      M(i, j) = number(row[static_cast<std::size_t>(j)], where, entry);
    }
  }
  return M;
}

inline std::vector<SignalInfo> signals_from_json(const json& object, const char* key,
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

inline json map_to_json(const StaticMap& m) {
  json j{{"type", identification::to_string(m.kind)}};
  if (m.kind != StaticMapKind::none) {
    j["lower"] = m.lower;
    j["upper"] = m.upper;
  }
  return j;
}

inline std::vector<StaticMap> maps_from_json(const json& object, const char* key,
                                             const std::string& where) {
  const json& value = field(object, key, where);
  if (!value.is_array()) fail(where + ": field \"" + key + "\" is not an array");
  std::vector<StaticMap> out;
  for (std::size_t i = 0; i < value.size(); ++i) {
    const std::string name = std::string(key) + "[" + std::to_string(i) + "]";
    const std::string type =
        text(field(value[i], "type", where + ": " + name), where, name + ".type");
    StaticMap m;
    if (type == "none") {
      m.kind = StaticMapKind::none;
    } else if (type == "deadzone" || type == "saturation") {
      m.kind = type == "deadzone" ? StaticMapKind::deadzone : StaticMapKind::saturation;
      m.lower = number(field(value[i], "lower", where + ": " + name), where, name + ".lower");
      m.upper = number(field(value[i], "upper", where + ": " + name), where, name + ".upper");
    } else {
      fail(where + ": field \"" + name + ".type\" is \"" + type +
           "\", expected none, deadzone or saturation");
    }
    out.push_back(m);
  }
  return out;
}

//! One fixed-size channel (Deadzone / Saturation / Identity) as a StaticMap.
template <typename NL>
StaticMap map_of(const NL& channel) {
  using Scalar = typename NL::ScalarType;
  if constexpr (std::is_same_v<NL, model::Deadzone<Scalar>>) {
    return {StaticMapKind::deadzone, static_cast<double>(channel.lower()),
            static_cast<double>(channel.upper())};
  } else if constexpr (std::is_same_v<NL, model::Saturation<Scalar>>) {
    return {StaticMapKind::saturation, static_cast<double>(channel.lower()),
            static_cast<double>(channel.upper())};
  } else {
    static_assert(std::is_same_v<NL, model::Identity<Scalar>>,
                  "model files store Deadzone, Saturation or Identity channels");
    return {};
  }
}

}  // namespace detail::model_file

//! Today's date in UTC, "YYYY-MM-DD" (for ModelProvenance::date).
[[nodiscard]] inline std::string utc_date_today() {
  const std::time_t now = std::chrono::system_clock::to_time_t(std::chrono::system_clock::now());
  std::tm utc{};
  gmtime_r(&now, &utc);
  char buffer[16];
  std::strftime(buffer, sizeof(buffer), "%Y-%m-%d", &utc);
  return buffer;
}

//! The model as JSON (format in docs/models/subspace.md). Throws Error naming the field when
//! sizes disagree or a number is not finite (JSON has no NaN).
[[nodiscard]] inline nlohmann::json to_json(const ModelFile& m) {
  namespace mf = detail::model_file;
  mf::validate(m, "to_json");
  nlohmann::json j;
  j["format"] = "endohaptics-model";
  j["version"] = ModelFile::format_version;
  j["kind"] = m.is_hammerstein_wiener() ? "hammerstein_wiener" : "state_space";
  j["sample_time_s"] = m.sample_time;
  j["states"] = m.A.rows();
  for (const char* key : {"inputs", "outputs"}) {
    nlohmann::json signals = nlohmann::json::array();
    for (const SignalInfo& s : std::string_view(key) == "inputs" ? m.inputs : m.outputs) {
      signals.push_back({{"name", s.name}, {"unit", s.unit}});
    }
    j[key] = std::move(signals);
  }
  j["A"] = mf::matrix_to_json(m.A);
  j["B"] = mf::matrix_to_json(m.B);
  j["C"] = mf::matrix_to_json(m.C);
  j["D"] = mf::matrix_to_json(m.D);
  j["x0"] = std::vector<double>(m.x0.data(), m.x0.data() + m.x0.size());
  if (m.is_hammerstein_wiener()) {
    j["input_nonlinearity"] = nlohmann::json::array();
    for (const auto& map : m.input_nonlinearity)
      j["input_nonlinearity"].push_back(mf::map_to_json(map));
    j["output_nonlinearity"] = nlohmann::json::array();
    for (const auto& map : m.output_nonlinearity) {
      j["output_nonlinearity"].push_back(mf::map_to_json(map));
    }
  }
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

//! Parses and validates a model from JSON; `source` (e.g. the path) prefixes error messages.
//! Throws Error naming the field and value: missing field, wrong type, wrong dimensions,
//! non-number (e.g. null, which is how NaN is written), bad breakpoints, sample time <= 0.
[[nodiscard]] inline ModelFile model_from_json(const nlohmann::json& j,
                                               const std::string& source = "model") {
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
  if (kind != "state_space" && kind != "hammerstein_wiener") {
    mf::fail(where + ": field \"kind\" is \"" + kind +
             "\", expected \"state_space\" or \"hammerstein_wiener\"");
  }
  ModelFile m;
  m.sample_time = mf::number(mf::field(j, "sample_time_s", where), where, "sample_time_s");
  const int n = mf::integer(mf::field(j, "states", where), where, "states");
  if (n < 1) mf::fail(where + ": field \"states\" must be >= 1, got " + std::to_string(n));
  m.inputs = mf::signals_from_json(j, "inputs", where);
  m.outputs = mf::signals_from_json(j, "outputs", where);
  const auto nu = static_cast<Eigen::Index>(m.inputs.size());
  const auto ny = static_cast<Eigen::Index>(m.outputs.size());
  m.A = mf::matrix_from_json(j, "A", n, n, "states", "states", where);
  m.B = mf::matrix_from_json(j, "B", n, nu, "states", "inputs", where);
  m.C = mf::matrix_from_json(j, "C", ny, n, "outputs", "states", where);
  m.D = mf::matrix_from_json(j, "D", ny, nu, "outputs", "inputs", where);
  const auto& x0 = mf::field(j, "x0", where);
  if (!x0.is_array() || static_cast<int>(x0.size()) != n) {
    mf::fail(where + ": field \"x0\" must be an array of " + std::to_string(n) +
             " numbers (states), got " + x0.dump());
  }
  m.x0.resize(n);
  for (int i = 0; i < n; ++i) {
    m.x0[i] = mf::number(x0[static_cast<std::size_t>(i)], where, "x0[" + std::to_string(i) + "]");
  }
  if (kind == "hammerstein_wiener") {
    m.input_nonlinearity = mf::maps_from_json(j, "input_nonlinearity", where);
    m.output_nonlinearity = mf::maps_from_json(j, "output_nonlinearity", where);
    if (m.input_nonlinearity.empty() && m.output_nonlinearity.empty()) {
      mf::fail(where +
               ": kind \"hammerstein_wiener\" needs input_nonlinearity or "
               "output_nonlinearity entries");
    }
  }
  const auto& p = mf::field(j, "provenance", where);
  if (!p.is_object()) mf::fail(where + ": field \"provenance\" is not an object");
  const std::string pw = where + ": provenance";
  m.provenance.method = mf::text(mf::field(p, "method", pw), where, "provenance.method");
  m.provenance.order = mf::integer(mf::field(p, "order", pw), where, "provenance.order");
  m.provenance.block_rows =
      mf::integer(mf::field(p, "block_rows", pw), where, "provenance.block_rows");
  m.provenance.date = mf::text(mf::field(p, "date", pw), where, "provenance.date");
  m.provenance.notes = mf::text(mf::field(p, "notes", pw), where, "provenance.notes");
  const auto& files = mf::field(p, "files", pw);
  const auto& fit = mf::field(p, "fit_percent", pw);
  if (!files.is_array()) mf::fail(where + ": field \"provenance.files\" is not an array");
  if (!fit.is_array()) mf::fail(where + ": field \"provenance.fit_percent\" is not an array");
  for (std::size_t i = 0; i < files.size(); ++i) {
    m.provenance.files.push_back(
        mf::text(files[i], where, "provenance.files[" + std::to_string(i) + "]"));
  }
  for (std::size_t i = 0; i < fit.size(); ++i) {
    m.provenance.fit_percent.push_back(
        mf::number(fit[i], where, "provenance.fit_percent[" + std::to_string(i) + "]"));
  }
  mf::validate(m, where);
  return m;
}

//! Writes `model` to `path` as indented JSON. Throws Error on invalid content (as to_json) or
//! when the file cannot be written.
inline void save_model(const std::filesystem::path& path, const ModelFile& model) {
  const nlohmann::json j = to_json(model);
  std::ofstream out(path);
  if (!out) detail::model_file::fail("save_model: cannot open " + path.string() + " for writing");
  out << j.dump(2) << '\n';
  if (!out) detail::model_file::fail("save_model: writing " + path.string() + " failed");
}

//! Reads and validates the model file at `path`. Throws Error naming the path and, for bad
//! content, the field and value (invalid JSON: the parser's message with the byte position).
[[nodiscard]] inline ModelFile load_model(const std::filesystem::path& path) {
  std::ifstream in(path);
  if (!in) detail::model_file::fail("model file " + path.string() + ": cannot be opened");
  std::stringstream text;
  text << in.rdbuf();
  const nlohmann::json j = nlohmann::json::parse(text.str(), nullptr, /*allow_exceptions=*/false);
  if (j.is_discarded()) {
    // Parse again with exceptions for the parser's message (position and token).
    std::string reason = "not valid JSON";
#if defined(__cpp_exceptions)
    try {
      const nlohmann::json unused = nlohmann::json::parse(text.str());
      static_cast<void>(unused);
    } catch (const nlohmann::json::parse_error& e) {
      reason = e.what();
    }
#endif
    detail::model_file::fail("model file " + path.string() + ": " + reason);
  }
  return model_from_json(j, path.string());
}

//! An identified SubspaceModel with signal names/units and provenance (method, order and
//! block rows are filled in from the model; date today if empty).
[[nodiscard]] inline ModelFile make_model_file(const identification::SubspaceModel& m,
                                               std::vector<SignalInfo> inputs,
                                               std::vector<SignalInfo> outputs,
                                               ModelProvenance provenance = {}) {
  ModelFile f;
  f.sample_time = m.sample_time;
  f.A = m.A;
  f.B = m.B;
  f.C = m.C;
  f.D = m.D;
  f.x0 = m.x0.size() == m.A.rows() ? m.x0 : Eigen::VectorXd(Eigen::VectorXd::Zero(m.A.rows()));
  f.inputs = std::move(inputs);
  f.outputs = std::move(outputs);
  f.provenance = std::move(provenance);
  if (f.provenance.method.empty()) f.provenance.method = identification::to_string(m.weighting);
  f.provenance.order = m.order;
  f.provenance.block_rows = m.block_rows;
  if (f.provenance.date.empty()) f.provenance.date = utc_date_today();
  detail::model_file::validate(f, "make_model_file");
  return f;
}

//! A fitted Hammerstein-Wiener model (maps included) with names, units and provenance.
[[nodiscard]] inline ModelFile make_model_file(const identification::HammersteinWienerFit& hw,
                                               std::vector<SignalInfo> inputs,
                                               std::vector<SignalInfo> outputs,
                                               ModelProvenance provenance = {}) {
  if (provenance.fit_percent.empty()) {
    provenance.fit_percent.assign(hw.fit.data(), hw.fit.data() + hw.fit.size());
  }
  ModelFile f =
      make_model_file(hw.linear, std::move(inputs), std::move(outputs), std::move(provenance));
  f.input_nonlinearity = hw.input;
  f.output_nonlinearity = hw.output;
  detail::model_file::validate(f, "make_model_file");
  return f;
}

//! A fixed-size StateSpace (x0 = its current state) with names, units and provenance.
template <int Nx, int Nu, int Ny, typename Scalar>
[[nodiscard]] ModelFile make_model_file(const model::StateSpace<Nx, Nu, Ny, Scalar>& ss,
                                        std::vector<SignalInfo> inputs,
                                        std::vector<SignalInfo> outputs,
                                        ModelProvenance provenance = {}) {
  identification::SubspaceModel m = identification::to_subspace_model(ss);
  m.block_rows = provenance.block_rows;
  return make_model_file(m, std::move(inputs), std::move(outputs), std::move(provenance));
}

//! A fixed-size HammersteinWiener whose maps are PerChannel Deadzone/Saturation/Identity.
template <typename Linear, typename InputNL, int Nu, typename OutputNL, int Ny>
[[nodiscard]] ModelFile make_model_file(
    const model::HammersteinWiener<Linear, model::PerChannel<InputNL, Nu>,
                                   model::PerChannel<OutputNL, Ny>>& hw,
    std::vector<SignalInfo> inputs, std::vector<SignalInfo> outputs,
    ModelProvenance provenance = {}) {
  ModelFile f =
      make_model_file(hw.linear(), std::move(inputs), std::move(outputs), std::move(provenance));
  for (int i = 0; i < Nu; ++i) {
    f.input_nonlinearity.push_back(detail::model_file::map_of(hw.input_nonlinearity().channel(i)));
  }
  for (int i = 0; i < Ny; ++i) {
    f.output_nonlinearity.push_back(
        detail::model_file::map_of(hw.output_nonlinearity().channel(i)));
  }
  return f;
}

//! The file's linear block as StateSpace<Nx, Nu, Ny, Scalar> starting from x0. Throws Error
//! when the file's sizes differ (the message gives both).
template <int Nx, int Nu, int Ny, typename Scalar = double>
[[nodiscard]] model::StateSpace<Nx, Nu, Ny, Scalar> to_state_space(
    const ModelFile& f, const std::string& source = "model") {
  identification::SubspaceModel m;
  m.A = f.A;
  m.B = f.B;
  m.C = f.C;
  m.D = f.D;
  m.x0 = f.x0;
  m.sample_time = f.sample_time;
#if defined(__cpp_exceptions)
  try {
    return identification::to_state_space<Nx, Nu, Ny, Scalar>(m);
  } catch (const Error& e) {
    detail::model_file::fail("model file " + source + ": " + e.what());
  }
#else
  return identification::to_state_space<Nx, Nu, Ny, Scalar>(m);
#endif
}

//! Loads a state-space model file into the fixed-size type (a Hammerstein-Wiener file's
//! linear block). Throws Error as load_model, or when the sizes differ from Nx, Nu, Ny.
template <int Nx, int Nu, int Ny, typename Scalar = double>
[[nodiscard]] model::StateSpace<Nx, Nu, Ny, Scalar> load_state_space(
    const std::filesystem::path& path) {
  return to_state_space<Nx, Nu, Ny, Scalar>(load_model(path), path.string());
}

//! Loads a Hammerstein-Wiener model file into HammersteinWiener<StateSpace<Nx, Nu, Ny>,
//! PerChannel<InputNL, Nu>, PerChannel<OutputNL, Ny>> (default: dead zones in, identity out,
//! the type of model::YawForceHW2016 for 6, 2, 1). A plain state-space file gets zero-width
//! dead zones. Throws Error as load_model, on other sizes, or maps the types cannot hold.
template <int Nx, int Nu, int Ny, typename Scalar = double,
          typename InputNL = model::Deadzone<Scalar>, typename OutputNL = model::Identity<Scalar>>
[[nodiscard]] auto load_hammerstein_wiener(const std::filesystem::path& path) {
  const ModelFile f = load_model(path);
  identification::HammersteinWienerFit hw;
  hw.linear.A = f.A;
  hw.linear.B = f.B;
  hw.linear.C = f.C;
  hw.linear.D = f.D;
  hw.linear.x0 = f.x0;
  hw.linear.sample_time = f.sample_time;
  hw.input = f.input_nonlinearity;
  hw.output = f.output_nonlinearity;
  if (hw.input.empty()) hw.input.assign(f.inputs.size(), {});
  if (hw.output.empty()) hw.output.assign(f.outputs.size(), {});
#if defined(__cpp_exceptions)
  try {
    return identification::to_hammerstein_wiener<Nx, Nu, Ny, Scalar, InputNL, OutputNL>(hw);
  } catch (const Error& e) {
    detail::model_file::fail("model file " + path.string() + ": " + e.what());
  }
#else
  return identification::to_hammerstein_wiener<Nx, Nu, Ny, Scalar, InputNL, OutputNL>(hw);
#endif
}

}  // namespace endohaptics::files
