//! @file
//! Identified-model files (JSON, nlohmann::json): a discrete state-space model (eq. 4.2), a
//! Hammerstein-Wiener model (figure 4.1) with dead-zone/saturation breakpoints, or a joint force
//! model's parameters (kinds "stall_hold", "push_load_observer" and "bidirectional_load_observer":
//! estimation/stall_hold.hpp, push_load_observer.hpp, bidirectional_load_observer.hpp), with
//! sample time in s, input/output names and units,
//! initial state and provenance (method, order, files, fit, date).
//! Loading validates every field and throws Error naming the file, the field and the value.
//! Format: docs/models/subspace.md, "Model files" (version 2; version 1 files migrate on read).
//! A joint model's parameters are the estimation type itself, read and written through its one
//! field list (files/parameter_json.hpp). Includes only core/, model/ and estimation/ (a program
//! that loads a model does not compile identification); the conversions from identification
//! results are in files/identified_model_file.hpp.
#pragma once

#include <Eigen/Core>
#include <algorithm>
#include <array>
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
#include <utility>
#include <variant>
#include <vector>
#include "endohaptics/core/separate_compilation.hpp"

#include "endohaptics/core/error.hpp"
#include "endohaptics/estimation/bidirectional_load_observer.hpp"
#include "endohaptics/estimation/current_offset_reference.hpp"
#include "endohaptics/estimation/push_load_observer.hpp"
#include "endohaptics/estimation/stall_hold.hpp"
#include "endohaptics/files/json_text.hpp"
#include "endohaptics/files/parameter_json.hpp"
#include "endohaptics/model/hammerstein_wiener.hpp"
#include "endohaptics/model/joint_model_bounds.hpp"
#include "endohaptics/model/state_space.hpp"
#include "endohaptics/model/static_map.hpp"
#include "endohaptics/model/static_nonlinearity.hpp"
#include "endohaptics/model/stop_operators.hpp"

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

//! What a model file describes ("kind").
enum class ModelKind : std::uint8_t {
  state_space,         //!< a linear state-space model (eq. 4.2)
  hammerstein_wiener,  //!< input maps, linear block, output maps (figure 4.1)
  stall_hold,          //!< estimation::StallHold (estimation/stall_hold.hpp)
  push_load_observer,  //!< estimation::PushLoadObserver (estimation/push_load_observer.hpp)
  //! estimation::BidirectionalLoadObserver (estimation/bidirectional_load_observer.hpp)
  bidirectional_load_observer,
};

//! The "kind" text of `kind` ("state_space", "hammerstein_wiener", "stall_hold",
//! "push_load_observer", "bidirectional_load_observer").
[[nodiscard]] constexpr std::string_view to_string(ModelKind kind) noexcept {
  switch (kind) {
    case ModelKind::state_space:
      return "state_space";
    case ModelKind::hammerstein_wiener:
      return "hammerstein_wiener";
    case ModelKind::stall_hold:
      return "stall_hold";
    case ModelKind::push_load_observer:
      return "push_load_observer";
    case ModelKind::bidirectional_load_observer:
      return "bidirectional_load_observer";
  }
  return "unknown";
}

//! The parameters of a joint-model kind, in the estimation type itself (its one field list,
//! `for_each_field`, is the file's "parameters" object; its sample_time is the file's
//! "sample_time_s"), or std::monostate for the linear kinds (state_space, hammerstein_wiener).
//! The order is ModelKind's, from stall_hold.
using JointModelParameters = std::variant<std::monostate, estimation::StallHoldParameters<double>,
                                          estimation::PushLoadObserverParameters<double>,
                                          estimation::BidirectionalLoadObserverParameters<double>>;

//! The current's offset reference to the command (estimation::CurrentOffsetReference) an
//! observer kind may carry: the file's "current_reference" object, and a third input.
using CurrentReference = estimation::CurrentOffsetReferenceParameters<double>;

//! The content of a model file, validated on load and save. The model (or a Hammerstein-Wiener
//! model's linear block) is the library's one linear-model type, `model::DynamicStateSpace<>`,
//! whose state is the file's x0; `model::StateSpace<Nx, Nu, Ny>(file.state_space)` gives the
//! fixed-size real-time model. An aggregate without a default constructor (a StateSpace has no
//! empty state): `model_from_json`, `make_model_file` or `ModelFile{.state_space = ...}`.
struct ModelFile {
  //! "version" written. Version 1 files (every observer parameter added after the first
  //! optional, the command reference inside "parameters") are migrated on read
  //! (detail::model_file::migrate).
  static constexpr int format_version = 2;
  //! Largest "states" accepted on load: the largest order identification fits
  //! (workflow::limits::max_order). A step costs states^2 multiply-adds: replaying a 100-state
  //! model over 600 000 samples (a minute at 0.1 ms) takes about 6e9, seconds, not hours.
  static constexpr int max_states = 100;
  //! Largest magnitude of a joint-model parameter and smallest |current_per_load| accepted: the
  //! bounds the estimation types check too (model/joint_model_bounds.hpp).
  static constexpr double max_parameter = model::max_joint_model_parameter;
  static constexpr double min_current_per_load = model::min_current_per_load;  //!< see above
  model::DynamicStateSpace<> state_space;  //!< A, B, C, D, sample time (s); state() = x0
  std::vector<SignalInfo> inputs{};        //!< nu entries
  std::vector<SignalInfo> outputs{};       //!< ny entries
  //! Hammerstein-Wiener maps, nu and ny entries; both empty for a plain state-space model.
  std::vector<model::StaticMap> input_nonlinearity{};
  std::vector<model::StaticMap> output_nonlinearity{};  //!< see input_nonlinearity
  ModelProvenance provenance{};                         //!< where it came from
  //! Output units, >= 0, linear kinds only (0: none): every output of the model goes through
  //! model::FreeMotionThreshold (0 at or below it, the estimate beyond twice it, continuous in
  //! between), wherever the model runs (replay, identify's scores, the bridge). identify
  //! --free-threshold auto sets it to the 99th percentile of |estimate| over the training samples
  //! whose true output is 0: what the model gives when nothing touches (JSON
  //! "free_motion_threshold", written when > 0).
  double free_motion_threshold = 0.0;
  //! Input 0's units (A for the force models' current), >= 0, linear kinds only (0: none):
  //! input 0 passes a play (backlash) operator of this half width, z = min(max(z, u - w), u + w)
  //! from z = 0, before the input nonlinearity, wherever the model runs (replay, identify's scores,
  //! the bridge: estimation::IdentifiedHammersteinWiener). The static friction of a joint pressed
  //! into an object: the current falls through the band while the force stays (identify
  //! --current-play; JSON "current_play", written when > 0).
  double current_play = 0.0;
  //! With current_play: the play's half width while the joint slides (Coulomb friction K_c <=
  //! the static K_s of current_play; model::friction_play), in [0, current_play]; none: the
  //! same as current_play, a plain play (identify --current-play-slide; JSON
  //! "current_play_slide", written when set).
  std::optional<double> current_play_slide{};
  //! With current_play: this times input 1 (the velocity) is the viscous friction's current, in
  //! the reported signals' signs; while the joint slides the play's output is input 0 less it
  //! and less the sliding half width (model::friction_play; identify --current-play-viscous; JSON
  //! "current_play_viscous", written when not 0).
  double current_play_viscous = 0.0;
  //! A joint-model kind's parameters (std::monostate: a linear kind). Then `state_space` is a
  //! placeholder (one state, all zero) that carries only the sample time (the parameters' own)
  //! and the sizes: 2 inputs (current A; velocity rad/s, for the observers the encoder velocity
  //! whose running sum times the sample time stands for the encoder angle: they use only its
  //! increments), with a current_reference a third (the current command); 1 output; no map.
  JointModelParameters parameters{};
  //! An observer kind's current offset reference to the command, or none.
  std::optional<CurrentReference> current_reference{};

  //! True when the file describes a Hammerstein-Wiener model ("kind": "hammerstein_wiener").
  [[nodiscard]] bool is_hammerstein_wiener() const noexcept {
    return !input_nonlinearity.empty() || !output_nonlinearity.empty();
  }
  //! What the file describes (a joint model's parameters win over the linear block).
  [[nodiscard]] ModelKind kind() const noexcept {
    if (parameters.index() != 0) {
      return static_cast<ModelKind>(static_cast<int>(ModelKind::stall_hold) +
                                    static_cast<int>(parameters.index()) - 1);
    }
    return is_hammerstein_wiener() ? ModelKind::hammerstein_wiener : ModelKind::state_space;
  }
  //! True for the kinds that are a joint force model, not a linear block (stall_hold,
  //! push_load_observer, bidirectional_load_observer): `state_space` is then only a placeholder.
  [[nodiscard]] bool is_joint_model() const noexcept { return parameters.index() != 0; }
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

//! Adds "A", "B", "C", "D", "x0" and, for a Hammerstein-Wiener model, the maps to `j`.
ENDOHAPTICS_DECL void add_linear_block(json& j, const ModelFile& m);

//! The "provenance" object of `j`; throws naming the field when missing or of the wrong type.
ENDOHAPTICS_DECL ModelProvenance provenance_from_json(const json& j, const std::string& where);

//! A joint-model kind ("stall_hold", "push_load_observer", "bidirectional_load_observer") from
//! version 2 `j`: its "parameters" object (every field of the type's list, no other), an
//! observer's optional "current_reference", no linear-block fields, 2 inputs (with a current
//! reference: 3) and 1 output; validated.
//! Throws Error naming the field.
ENDOHAPTICS_DECL ModelFile joint_model_from_json(const json& j, const std::string& kind,
                                                 double sample_time, std::vector<SignalInfo> inputs,
                                                 std::vector<SignalInfo> outputs,
                                                 const std::string& where);

ENDOHAPTICS_DECL std::vector<StaticMap> maps_from_json(const json& object, const char* key,
                                                       const std::string& where);

//! A version 1 file's JSON as version 2 (`j` is an object whose "version" is 1): a
//! push_load_observer's later fields (the back-driven map, all four or none; load_per_angle)
//! get the values that mean "none", an observer's command_gain and reference_offset (both or
//! none; a command_gain of 0 is none) move to "current_reference". Throws naming the field.
ENDOHAPTICS_DECL void migrate(nlohmann::json& j, const std::string& where);

//! The placeholder linear block of a joint-model kind: one state, all zero, `nu` inputs, one
//! output, the sample time (s). Throws Error on a sample time that is not finite and > 0.
ENDOHAPTICS_DECL model::DynamicStateSpace<> joint_model_placeholder(Eigen::Index nu,
                                                                    double sample_time);

//! Throws naming `where` when `f` is a joint-model kind (no linear block to load).
ENDOHAPTICS_DECL void require_linear(const ModelFile& f, const std::string& where);

//! Throws naming `where` unless `f` is of kind `kind`.
ENDOHAPTICS_DECL void require_kind(const ModelFile& f, ModelKind kind, const std::string& where);

}  // namespace detail::model_file

//! A joint-model file: `parameters` (its sample time the file's), the inputs (current,
//! velocity; with `reference` a third, the current command) and one output with names and
//! units, provenance (date today if empty). Throws Error "make_joint_model_file: field
//! \"parameters.<name>\" ..." when a value breaks its type's rule, or on other signal counts.
[[nodiscard]] ENDOHAPTICS_DECL ModelFile
make_joint_model_file(JointModelParameters parameters, std::vector<SignalInfo> inputs,
                      std::vector<SignalInfo> outputs, ModelProvenance provenance = {},
                      std::optional<CurrentReference> reference = std::nullopt);

//! The kind whose parameters are `P` (an alternative of JointModelParameters but the first).
template <typename P, std::size_t I = 1>
[[nodiscard]] constexpr ModelKind joint_model_kind() noexcept {
  if constexpr (std::is_same_v<std::variant_alternative_t<I, JointModelParameters>, P>) {
    return static_cast<ModelKind>(static_cast<int>(ModelKind::stall_hold) + static_cast<int>(I) -
                                  1);
  } else {
    return joint_model_kind<P, I + 1>();
  }
}

//! The parameters of a joint-model file as `P` (estimation::StallHoldParameters<double>, ...,
//! its sample time included). Throws Error "<where>: the model file is of kind ..." naming both
//! kinds when `f` holds another.
template <typename P>
[[nodiscard]] const P& joint_model_parameters(const ModelFile& f,
                                              std::string_view where = "joint_model_parameters") {
  const P* p = std::get_if<P>(&f.parameters);
  if (p == nullptr) {
    detail::model_file::require_kind(f, joint_model_kind<P>(), std::string(where));
  }
  return *p;
}

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
  detail::model_file::require_linear(f, "model file " + path.string());
  return detail::model_file::with_context("model file " + path.string(), [&] {
    return model::StateSpace<Nx, Nu, Ny, Scalar>(f.state_space);
  });
}

//! A loaded model file as HammersteinWiener<StateSpace<Nx, Nu, Ny>, PerChannel<InputNL, Nu>,
//! PerChannel<OutputNL, Ny>> (default: dead zones in, identity out, the type of
//! model::YawForceHW2016 for 6, 2, 1) with model::to_hammerstein_wiener. A plain state-space file
//! gets zero-width dead zones. Throws Error for a joint-model kind, on other sizes, or maps the
//! types cannot hold (the message prefixed with `where`).
template <int Nx, int Nu, int Ny, typename Scalar = double,
          typename InputNL = model::Deadzone<Scalar>, typename OutputNL = model::Identity<Scalar>>
[[nodiscard]] auto hammerstein_wiener_from(const ModelFile& f, const std::string& where) {
  detail::model_file::require_linear(f, where);
  std::vector<model::StaticMap> input = f.input_nonlinearity;
  std::vector<model::StaticMap> output = f.output_nonlinearity;
  if (input.empty()) input.assign(f.inputs.size(), {});
  if (output.empty()) output.assign(f.outputs.size(), {});
  return detail::model_file::with_context(where, [&] {
    return model::to_hammerstein_wiener<Nx, Nu, Ny, Scalar, InputNL, OutputNL>(f.state_space, input,
                                                                               output);
  });
}

//! Loads a Hammerstein-Wiener model file: load_model, then hammerstein_wiener_from (errors
//! prefixed with the path).
template <int Nx, int Nu, int Ny, typename Scalar = double,
          typename InputNL = model::Deadzone<Scalar>, typename OutputNL = model::Identity<Scalar>>
[[nodiscard]] auto load_hammerstein_wiener(const std::filesystem::path& path) {
  return hammerstein_wiener_from<Nx, Nu, Ny, Scalar, InputNL, OutputNL>(
      load_model(path), "model file " + path.string());
}

}  // namespace endohaptics::files

#if !defined(ENDOHAPTICS_SEPARATE_COMPILATION)
#include "endohaptics/files/impl/model_file.ipp"
#endif
