//! @file
//! Identified-model files (JSON, nlohmann::json): a discrete state-space model (eq. 4.2) or a
//! Hammerstein-Wiener model (figure 4.1) with dead-zone/saturation breakpoints, sample time in s,
//! input/output names and units, initial state and provenance (method, order, files, fit, date).
//! Loading validates every field and throws Error naming the file, the field and the value.
//! Format: docs/models/subspace.md, "Model files". Includes only core/ and model/ (a program
//! that loads a model does not compile identification); the conversions from identification
//! results are in files/identified_model_file.hpp.
#pragma once

#include <Eigen/Core>
#include <chrono>
#include <cmath>
#include <cstdint>
#include <ctime>
#include <filesystem>
#include <fstream>
#include <limits>
#include <nlohmann/json.hpp>
#include <optional>
#include <sstream>
#include <string>
#include <string_view>
#include <type_traits>
#include <vector>
#include "endohaptics/core/separate_compilation.hpp"

#include "endohaptics/core/error.hpp"
#include "endohaptics/files/json_text.hpp"
#include "endohaptics/model/hammerstein_wiener.hpp"
#include "endohaptics/model/state_space.hpp"
#include "endohaptics/model/static_map.hpp"
#include "endohaptics/model/static_nonlinearity.hpp"

namespace endohaptics::files {

//! Largest model file `load_model` reads, bytes (a 1000-state model's A alone is ~25 MB of text).
inline constexpr std::size_t model_file_max_bytes = std::size_t{64} << 20;
//! Deepest nesting of arrays and objects accepted in a model file (the format needs 4).
inline constexpr int model_file_max_depth = 32;

//! Name and unit of one input or output signal (e.g. {"current", "A"}).
struct SignalInfo {
  std::string name;  //!< signal name
  std::string unit;  //!< unit symbol ("" for dimensionless)
};

//! Where a model came from.
struct ModelProvenance {
  std::string method{};               //!< e.g. "moesp", "n4sid", "cva", "worksheet appendix C"
  int order = 0;                      //!< model order n
  int block_rows = 0;                 //!< subspace horizon s (0: not applicable)
  std::vector<std::string> files{};   //!< data files it was identified from
  std::vector<double> fit_percent{};  //!< NRMSE fit per output, %, on the data named in `notes`
  std::string date{};                 //!< ISO 8601 (UTC) date of identification
  std::string notes{};                //!< free text
};

//! The content of a model file, validated on load and save. The model (or a Hammerstein-Wiener
//! model's linear block) is the library's one linear-model type, `model::DynamicStateSpace<>`,
//! whose state is the file's x0; `model::StateSpace<Nx, Nu, Ny>(file.state_space)` gives the
//! fixed-size real-time model. An aggregate without a default constructor (a StateSpace has no
//! empty state): `model_from_json`, `make_model_file` or `ModelFile{.state_space = ...}`.
struct ModelFile {
  static constexpr int format_version = 1;  //!< "version" written and accepted
  //! Largest "states" accepted on load: A alone is states^2 numbers (8 MB at 1000).
  static constexpr int max_states = 1000;
  model::DynamicStateSpace<> state_space;  //!< A, B, C, D, sample time (s); state() = x0
  std::vector<SignalInfo> inputs{};        //!< nu entries
  std::vector<SignalInfo> outputs{};       //!< ny entries
  //! Hammerstein-Wiener maps, nu and ny entries; both empty for a plain state-space model.
  std::vector<model::StaticMap> input_nonlinearity{};
  std::vector<model::StaticMap> output_nonlinearity{};  //!< see input_nonlinearity
  ModelProvenance provenance{};                         //!< where it came from

  //! True when the file describes a Hammerstein-Wiener model ("kind": "hammerstein_wiener").
  [[nodiscard]] bool is_hammerstein_wiener() const noexcept {
    return !input_nonlinearity.empty() || !output_nonlinearity.empty();
  }
};

namespace detail::model_file {

using model::StaticMap;
using model::StaticMapKind;
using nlohmann::json;

using endohaptics::detail::fail;

using endohaptics::detail::format_number;

//! Throws unless the signal and map counts agree with the model's sizes and every number is
//! finite (A, B, C, D and the sample time are checked by the StateSpace itself); `where`
//! prefixes the message.
ENDOHAPTICS_DECL void validate(const ModelFile& m, const std::string& where);

using endohaptics::detail::with_context;

ENDOHAPTICS_DECL json matrix_to_json(const Eigen::MatrixXd& M);

//! Reads field `key` of `object`; throws naming it when missing.
inline const json& field(const json& object, const char* key, const std::string& where) {
  const auto it = object.find(key);
  if (it == object.end()) fail(where + ": missing field \"" + key + "\"");
  return *it;
}

ENDOHAPTICS_DECL double number(const json& value, const std::string& where,
                               const std::string& name);

ENDOHAPTICS_DECL std::string text(const json& value, const std::string& where,
                                  const std::string& name);

//! An integer field in [min, max]; a value outside (e.g. 4294967298, which an int would wrap
//! to 2) throws naming the field, the value and the range.
ENDOHAPTICS_DECL int integer(const json& value, const std::string& where, const std::string& name,
                             int min = std::numeric_limits<int>::min(),
                             int max = std::numeric_limits<int>::max());

//! A matrix stored as an array of `rows` rows of `cols` numbers.
ENDOHAPTICS_DECL Eigen::MatrixXd matrix_from_json(const json& object, const char* key,
                                                  Eigen::Index rows, Eigen::Index cols,
                                                  const char* row_name, const char* col_name,
                                                  const std::string& where);

ENDOHAPTICS_DECL std::vector<SignalInfo> signals_from_json(const json& object, const char* key,
                                                           const std::string& where);

ENDOHAPTICS_DECL json map_to_json(const StaticMap& m);

ENDOHAPTICS_DECL std::vector<StaticMap> maps_from_json(const json& object, const char* key,
                                                       const std::string& where);

}  // namespace detail::model_file

//! Today's date in UTC, "YYYY-MM-DD" (for ModelProvenance::date).
[[nodiscard]] ENDOHAPTICS_DECL std::string utc_date_today();

//! The model as JSON (format in docs/models/subspace.md). Throws Error naming the field when
//! sizes disagree or a number is not finite (JSON has no NaN).
[[nodiscard]] ENDOHAPTICS_DECL nlohmann::json to_json(const ModelFile& m);

//! Parses and validates a model from JSON; `source` (e.g. the path) prefixes error messages.
//! Throws Error naming the field and value: missing field, wrong type, wrong dimensions,
//! non-number (e.g. null, which is how NaN is written), bad breakpoints, sample time <= 0,
//! "states" outside [1, ModelFile::max_states], an integer field that does not fit an int.
[[nodiscard]] ENDOHAPTICS_DECL ModelFile model_from_json(const nlohmann::json& j,
                                                         const std::string& source = "model");

//! Writes `model` to `path` as indented JSON. Throws Error on invalid content (as to_json) or
//! when the file cannot be written.
ENDOHAPTICS_DECL void save_model(const std::filesystem::path& path, const ModelFile& model);

//! Reads and validates the model file at `path`. Throws Error naming the path and, for bad
//! content, the field and value (invalid JSON: the parser's message with the byte position).
[[nodiscard]] ENDOHAPTICS_DECL ModelFile load_model(const std::filesystem::path& path);

//! A StateSpace of any sizes (x0 = its current state) with names, units and provenance (order
//! filled in from the model; date today if empty). Throws Error when the signal counts differ
//! from the model's sizes or a number is not finite.
template <int Nx, int Nu, int Ny, typename Scalar>
[[nodiscard]] ModelFile make_model_file(const model::StateSpace<Nx, Nu, Ny, Scalar>& ss,
                                        std::vector<SignalInfo> inputs,
                                        std::vector<SignalInfo> outputs,
                                        ModelProvenance provenance = {}) {
  ModelFile f{.state_space = model::DynamicStateSpace<>(ss),
              .inputs = std::move(inputs),
              .outputs = std::move(outputs),
              .provenance = std::move(provenance)};
  f.provenance.order = f.state_space.state_size();
  if (f.provenance.date.empty()) f.provenance.date = utc_date_today();
  detail::model_file::validate(f, "make_model_file");
  return f;
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
    f.input_nonlinearity.push_back(model::to_static_map(hw.input_nonlinearity().channel(i)));
  }
  for (int i = 0; i < Ny; ++i) {
    f.output_nonlinearity.push_back(model::to_static_map(hw.output_nonlinearity().channel(i)));
  }
  detail::model_file::validate(f, "make_model_file");
  return f;
}

//! Loads a state-space model file into the fixed-size type (a Hammerstein-Wiener file's
//! linear block), starting from the file's x0: StateSpace's converting constructor on
//! `load_model(path).state_space`, its message prefixed with the path. Throws Error as
//! load_model, or when the sizes differ from Nx, Nu, Ny.
template <int Nx, int Nu, int Ny, typename Scalar = double>
[[nodiscard]] model::StateSpace<Nx, Nu, Ny, Scalar> load_state_space(
    const std::filesystem::path& path) {
  const ModelFile f = load_model(path);
  return detail::model_file::with_context("model file " + path.string(), [&] {
    return model::StateSpace<Nx, Nu, Ny, Scalar>(f.state_space);
  });
}

//! Loads a Hammerstein-Wiener model file into HammersteinWiener<StateSpace<Nx, Nu, Ny>,
//! PerChannel<InputNL, Nu>, PerChannel<OutputNL, Ny>> (default: dead zones in, identity out,
//! the type of model::YawForceHW2016 for 6, 2, 1) with model::to_hammerstein_wiener. A plain
//! state-space file gets zero-width dead zones. Throws Error as load_model, on other sizes, or
//! maps the types cannot hold (the message prefixed with the path).
template <int Nx, int Nu, int Ny, typename Scalar = double,
          typename InputNL = model::Deadzone<Scalar>, typename OutputNL = model::Identity<Scalar>>
[[nodiscard]] auto load_hammerstein_wiener(const std::filesystem::path& path) {
  const ModelFile f = load_model(path);
  std::vector<model::StaticMap> input = f.input_nonlinearity;
  std::vector<model::StaticMap> output = f.output_nonlinearity;
  if (input.empty()) input.assign(f.inputs.size(), {});
  if (output.empty()) output.assign(f.outputs.size(), {});
  return detail::model_file::with_context("model file " + path.string(), [&] {
    return model::to_hammerstein_wiener<Nx, Nu, Ny, Scalar, InputNL, OutputNL>(f.state_space, input,
                                                                               output);
  });
}

}  // namespace endohaptics::files

#if !defined(ENDOHAPTICS_SEPARATE_COMPILATION)
#include "endohaptics/files/impl/model_file.ipp"
#endif
