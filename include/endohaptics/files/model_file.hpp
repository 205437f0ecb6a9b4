//! @file
//! Identified-model files (JSON, nlohmann::json): a discrete state-space model (eq. 4.2), a
//! Hammerstein-Wiener model (figure 4.1) with dead-zone/saturation breakpoints, or a joint force
//! model's parameters (kinds "stall_hold", "push_load_observer" and "bidirectional_load_observer":
//! estimation/stall_hold.hpp, push_load_observer.hpp, bidirectional_load_observer.hpp), with
//! sample time in s, input/output names and units,
//! initial state and provenance (method, order, files, fit, date).
//! Loading validates every field and throws Error naming the file, the field and the value.
//! Format: docs/models/subspace.md, "Model files". Includes only core/ and model/ (a program
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
#include <vector>
#include "endohaptics/core/separate_compilation.hpp"

#include "endohaptics/core/error.hpp"
#include "endohaptics/files/json_text.hpp"
#include "endohaptics/model/hammerstein_wiener.hpp"
#include "endohaptics/model/joint_model_bounds.hpp"
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

//! Kind "stall_hold": the parameters of estimation::StallHold (same names, same units: A, rad/s,
//! s, output unit per A) without the sample time (the file's "sample_time_s"). Plain numbers here
//! so that this header stays below estimation/; stall_hold_parameters() converts.
struct StallHoldSettings {
  double current_deadzone = 0.20;        //!< A, >= 0: the static friction current
  double velocity_threshold = 0.05;      //!< rad/s, >= 0: at or below, the value is held
  double velocity_time_constant = 0.03;  //!< s, >= 0: first-order low-pass of the velocity
  double output_time_constant = 0.3;     //!< s, >= 0: first-order lag of the output
  double gain = 1.0;                     //!< output units per A beyond the dead zone, finite
  std::string side = "both";             //!< "both", "positive" or "negative"
};

//! Kind "push_load_observer": the parameters of estimation::PushLoadObserver (same names and
//! units; load in the output's unit) without the sample time (the file's "sample_time_s").
struct PushLoadObserverSettings {
  double current_cutoff = 10;          //!< Hz, in (0, Nyquist)
  double velocity_cutoff = 20;         //!< Hz, in (0, Nyquist)
  double direction_scale = 0.05;       //!< rad, > 0
  double velocity_threshold = 0.05;    //!< rad/s, >= 0
  double direction_threshold = 0.5;    //!< in (0, 1]
  double push_sign = 1;                //!< +1 or -1
  double current_per_load = 1;         //!< A per load unit, finite and non-zero
  double current_offset = 0;           //!< A
  double current_per_velocity = 0;     //!< A s/rad
  double measurement_variance = 1e-4;  //!< A^2, > 0
  double process_variance = 1e-8;      //!< load unit^2 per step, >= 0
  double initial_load = 0;             //!< load units
  double initial_variance = 1e-2;      //!< load unit^2, >= 0
  double output_offset = 0;            //!< load units
  double output_slope = 0;             //!< dimensionless
  //! A per load unit while back-driven, 0 (none: files before it was added) or non-zero
  double back_current_per_load = 0;
  double back_current_offset = 0;        //!< A
  double back_current_per_velocity = 0;  //!< A s/rad
  double back_variance = 1;              //!< load unit^2, > 0
  double load_per_angle = 0;             //!< k_q, load units per rad (0 in older files)
  //! G, A per command unit, of the current's offset reference (current_offset_reference.hpp): 0
  //! (none: two inputs) or non-zero (then a third input, the commanded current)
  double command_gain = 0;
  double reference_offset = 0;  //!< b_ref, A
};

//! Kind "bidirectional_load_observer": the parameters of estimation::BidirectionalLoadObserver
//! (same names and units; load in the output's unit) without the sample time, and the current's
//! offset reference as for the push-load observer. The arrays hold one value per stop operator.
struct BidirectionalObserverSettings {
  //! One value per stop operator.
  using Stops = std::array<double, static_cast<std::size_t>(model::bidirectional_observer_stops)>;
  double current_cutoff = 10;                                         //!< Hz, in (0, Nyquist)
  double velocity_cutoff = 20;                                        //!< Hz, in (0, Nyquist)
  double direction_scale = 0.05;                                      //!< rad, > 0
  double velocity_threshold = 0.05;                                   //!< rad/s, >= 0
  double direction_threshold = 0.5;                                   //!< in (0, 1]
  Stops stop_thresholds{0.005, 0.02, 0.05, 0.1, 0.2, 0.3, 0.4, 0.5};  //!< rad, increasing, > 0
  double start_travel = 0.005;                                        //!< rad, >= 0
  double forward_gain = 1;         //!< A per load unit, of magnitude >= |forward_gain_stroke| / 0.9
  double forward_gain_stroke = 0;  //!< A per load unit per unit of the widest operator
  double forward_offset = 0;       //!< A
  double forward_offset_stroke = 0;      //!< A
  double backward_gain = 1;              //!< A per load unit, of forward_gain's sign
  double backward_gain_stroke = 0;       //!< A per load unit
  double backward_offset = 0;            //!< A
  double backward_offset_stroke = 0;     //!< A
  double forward_variance = 1;           //!< load unit^2, in [1e-12, 1e6]
  double backward_variance = 1;          //!< load unit^2, in [1e-12, 1e6]
  double load_process_variance = 0;      //!< load unit^2 per step, >= 0
  double friction_variance = 1;          //!< load unit^2, >= 0
  double friction_process_variance = 0;  //!< load unit^2 per step, >= 0
  double initial_load = 0;               //!< load units
  double initial_variance = 1;           //!< load unit^2, >= 0
  double output_offset = 0;              //!< load units
  Stops output_shape{};                  //!< load units
  Stops output_shape_per_load{};         //!< dimensionless
  double command_gain = 0;      //!< A per command unit: 0 (two inputs) or non-zero (a third)
  double reference_offset = 0;  //!< A
};

//! The content of a model file, validated on load and save. The model (or a Hammerstein-Wiener
//! model's linear block) is the library's one linear-model type, `model::DynamicStateSpace<>`,
//! whose state is the file's x0; `model::StateSpace<Nx, Nu, Ny>(file.state_space)` gives the
//! fixed-size real-time model. An aggregate without a default constructor (a StateSpace has no
//! empty state): `model_from_json`, `make_model_file` or `ModelFile{.state_space = ...}`.
struct ModelFile {
  static constexpr int format_version = 1;  //!< "version" written and accepted
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
  //! Kind "stall_hold": its parameters. Then `state_space` is a placeholder (one state, all
  //! zero) that carries only the sample time and the sizes (2 inputs: current A, velocity
  //! rad/s; 1 output); no map may be set.
  std::optional<StallHoldSettings> stall_hold{};
  //! Kind "push_load_observer": its parameters; `state_space` a placeholder as for stall_hold
  //! (2 inputs: current A, encoder velocity rad/s, whose running sum times the sample time stands
  //! for the encoder angle: the observer uses only its increments; with a non-zero command_gain
  //! a third, the current command; 1 output: the load).
  std::optional<PushLoadObserverSettings> push_load_observer{};
  //! Kind "bidirectional_load_observer": its parameters; `state_space` a placeholder and the
  //! inputs as for push_load_observer.
  std::optional<BidirectionalObserverSettings> bidirectional_load_observer{};

  //! True when the file describes a Hammerstein-Wiener model ("kind": "hammerstein_wiener").
  [[nodiscard]] bool is_hammerstein_wiener() const noexcept {
    return !input_nonlinearity.empty() || !output_nonlinearity.empty();
  }
  //! What the file describes (a joint model's parameters win over the linear block).
  [[nodiscard]] ModelKind kind() const noexcept {
    if (stall_hold) return ModelKind::stall_hold;
    if (push_load_observer) return ModelKind::push_load_observer;
    if (bidirectional_load_observer) return ModelKind::bidirectional_load_observer;
    return is_hammerstein_wiener() ? ModelKind::hammerstein_wiener : ModelKind::state_space;
  }
  //! True for the kinds that are a joint force model, not a linear block (stall_hold,
  //! push_load_observer, bidirectional_load_observer): `state_space` is then only a placeholder.
  [[nodiscard]] bool is_joint_model() const noexcept {
    return stall_hold.has_value() || push_load_observer.has_value() ||
           bidirectional_load_observer.has_value();
  }
  //! The current's offset reference to the command (G, b_ref) of an observer kind: G is 0 when
  //! there is none (and for the other kinds).
  [[nodiscard]] std::pair<double, double> command_reference() const noexcept {
    if (push_load_observer) {
      return {push_load_observer->command_gain, push_load_observer->reference_offset};
    }
    if (bidirectional_load_observer) {
      return {bidirectional_load_observer->command_gain,
              bidirectional_load_observer->reference_offset};
    }
    return {0.0, 0.0};
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

//! Adds "A", "B", "C", "D", "x0" and, for a Hammerstein-Wiener model, the maps to `j`.
ENDOHAPTICS_DECL void add_linear_block(json& j, const ModelFile& m);

//! The "provenance" object of `j`; throws naming the field when missing or of the wrong type.
ENDOHAPTICS_DECL ModelProvenance provenance_from_json(const json& j, const std::string& where);

//! A joint-model kind ("stall_hold", "push_load_observer", "bidirectional_load_observer") from
//! `j`: its "parameters" object (every field required except those added later, unknown fields
//! refused), no linear-block fields, 2 inputs (an observer with a command reference: 3) and 1
//! output; validated.
//! Throws Error naming the field.
ENDOHAPTICS_DECL ModelFile joint_model_from_json(const json& j, const std::string& kind,
                                                 double sample_time, std::vector<SignalInfo> inputs,
                                                 std::vector<SignalInfo> outputs,
                                                 const std::string& where);

ENDOHAPTICS_DECL std::vector<StaticMap> maps_from_json(const json& object, const char* key,
                                                       const std::string& where);

//! Throws "<where>: field \"parameters.<name>\" must be <rule>, got <value>" unless `ok`.
ENDOHAPTICS_DECL void require_parameter(bool ok, const std::string& where, const char* name,
                                        double value, const char* rule);

//! Throws naming the field unless every value of `p` is in its range (StallHoldSettings).
ENDOHAPTICS_DECL void validate_settings(const StallHoldSettings& p, const std::string& where);

//! Throws naming the field unless every value of `p` is in its range, the cut-offs below the
//! Nyquist frequency of `sample_time` s (PushLoadObserverSettings).
ENDOHAPTICS_DECL void validate_settings(const PushLoadObserverSettings& p, double sample_time,
                                        const std::string& where);

//! As above, for BidirectionalObserverSettings (the rules of
//! estimation::BidirectionalLoadObserverParameters::validate).
ENDOHAPTICS_DECL void validate_settings(const BidirectionalObserverSettings& p, double sample_time,
                                        const std::string& where);

//! The placeholder linear block of a joint-model kind: one state, all zero, `nu` inputs, one
//! output, the sample time (s). Throws Error on a sample time that is not finite and > 0.
ENDOHAPTICS_DECL model::DynamicStateSpace<> joint_model_placeholder(Eigen::Index nu,
                                                                    double sample_time);

//! Throws naming `where` when `f` is a joint-model kind (no linear block to load).
ENDOHAPTICS_DECL void require_linear(const ModelFile& f, const std::string& where);

//! Throws naming `where` unless `f` is of kind `kind`.
ENDOHAPTICS_DECL void require_kind(const ModelFile& f, ModelKind kind, const std::string& where);

}  // namespace detail::model_file

//! A "stall_hold" model file: `settings`, the sample time (s), the two inputs (current,
//! velocity) and one output with names and units, provenance (date today if empty). Throws
//! Error naming the field when a value is out of range (the rules of StallHoldSettings).
[[nodiscard]] ENDOHAPTICS_DECL ModelFile make_stall_hold_file(const StallHoldSettings& settings,
                                                              double sample_time,
                                                              std::vector<SignalInfo> inputs,
                                                              std::vector<SignalInfo> outputs,
                                                              ModelProvenance provenance = {});

//! A "push_load_observer" model file, as make_stall_hold_file.
[[nodiscard]] ENDOHAPTICS_DECL ModelFile make_push_load_observer_file(
    const PushLoadObserverSettings& settings, double sample_time, std::vector<SignalInfo> inputs,
    std::vector<SignalInfo> outputs, ModelProvenance provenance = {});

//! A "bidirectional_load_observer" model file, as make_stall_hold_file.
[[nodiscard]] ENDOHAPTICS_DECL ModelFile
make_bidirectional_observer_file(const BidirectionalObserverSettings& settings, double sample_time,
                                 std::vector<SignalInfo> inputs, std::vector<SignalInfo> outputs,
                                 ModelProvenance provenance = {});

//! The parameters of a "stall_hold" file as `Parameters` (estimation::StallHoldParameters<S>;
//! a template so that this header does not include estimation/): every field and the sample
//! time. Throws Error naming the kind when `f` is of another kind.
template <typename Parameters>
[[nodiscard]] Parameters stall_hold_parameters(const ModelFile& f) {
  detail::model_file::require_kind(f, ModelKind::stall_hold, "stall_hold_parameters");
  using S = decltype(Parameters{}.gain);
  using Side = decltype(Parameters{}.side);
  const StallHoldSettings& m = *f.stall_hold;
  Parameters p;
  p.current_deadzone = static_cast<S>(m.current_deadzone);
  p.velocity_threshold = static_cast<S>(m.velocity_threshold);
  p.velocity_time_constant = static_cast<S>(m.velocity_time_constant);
  p.output_time_constant = static_cast<S>(m.output_time_constant);
  p.gain = static_cast<S>(m.gain);
  p.side = m.side == "positive"   ? Side::positive
           : m.side == "negative" ? Side::negative
                                  : Side::both;
  p.sample_time = static_cast<S>(f.state_space.sample_time());
  return p;
}

//! The parameters of a "push_load_observer" file as `Parameters`
//! (estimation::PushLoadObserverParameters<S>), as stall_hold_parameters.
template <typename Parameters>
[[nodiscard]] Parameters push_load_observer_parameters(const ModelFile& f) {
  detail::model_file::require_kind(f, ModelKind::push_load_observer,
                                   "push_load_observer_parameters");
  using S = decltype(Parameters{}.current_cutoff);
  const PushLoadObserverSettings& m = *f.push_load_observer;
  Parameters p;
  p.current_cutoff = static_cast<S>(m.current_cutoff);
  p.velocity_cutoff = static_cast<S>(m.velocity_cutoff);
  p.direction_scale = static_cast<S>(m.direction_scale);
  p.velocity_threshold = static_cast<S>(m.velocity_threshold);
  p.direction_threshold = static_cast<S>(m.direction_threshold);
  p.push_sign = static_cast<S>(m.push_sign);
  p.current_per_load = static_cast<S>(m.current_per_load);
  p.current_offset = static_cast<S>(m.current_offset);
  p.current_per_velocity = static_cast<S>(m.current_per_velocity);
  p.measurement_variance = static_cast<S>(m.measurement_variance);
  p.process_variance = static_cast<S>(m.process_variance);
  p.initial_load = static_cast<S>(m.initial_load);
  p.initial_variance = static_cast<S>(m.initial_variance);
  p.output_offset = static_cast<S>(m.output_offset);
  p.output_slope = static_cast<S>(m.output_slope);
  p.back_current_per_load = static_cast<S>(m.back_current_per_load);
  p.back_current_offset = static_cast<S>(m.back_current_offset);
  p.back_current_per_velocity = static_cast<S>(m.back_current_per_velocity);
  p.back_variance = static_cast<S>(m.back_variance);
  p.load_per_angle = static_cast<S>(m.load_per_angle);
  p.sample_time = static_cast<S>(f.state_space.sample_time());
  return p;
}

//! The current's offset reference of an observer file ("push_load_observer",
//! "bidirectional_load_observer") as `Parameters`
//! (estimation::CurrentOffsetReferenceParameters<S>), or none when its command_gain is 0 (or the
//! file is of another kind).
template <typename Parameters>
[[nodiscard]] std::optional<Parameters> current_offset_reference_parameters(const ModelFile& f) {
  const auto [gain, offset] = f.command_reference();
  if (gain == 0) return std::nullopt;
  using S = decltype(Parameters{}.command_gain);
  Parameters p;
  p.command_gain = static_cast<S>(gain);
  p.reference_offset = static_cast<S>(offset);
  return p;
}

//! The parameters of a "bidirectional_load_observer" file as `Parameters`
//! (estimation::BidirectionalLoadObserverParameters<S>), as stall_hold_parameters.
template <typename Parameters>
[[nodiscard]] Parameters bidirectional_observer_parameters(const ModelFile& f) {
  detail::model_file::require_kind(f, ModelKind::bidirectional_load_observer,
                                   "bidirectional_observer_parameters");
  using S = decltype(Parameters{}.current_cutoff);
  static_assert(decltype(Parameters{}.stop_thresholds)::SizeAtCompileTime ==
                    model::bidirectional_observer_stops,
                "the model files hold bidirectional_observer_stops stop operators");
  const BidirectionalObserverSettings& m = *f.bidirectional_load_observer;
  Parameters p;
  p.current_cutoff = static_cast<S>(m.current_cutoff);
  p.velocity_cutoff = static_cast<S>(m.velocity_cutoff);
  p.direction_scale = static_cast<S>(m.direction_scale);
  p.velocity_threshold = static_cast<S>(m.velocity_threshold);
  p.direction_threshold = static_cast<S>(m.direction_threshold);
  p.start_travel = static_cast<S>(m.start_travel);
  p.forward_gain = static_cast<S>(m.forward_gain);
  p.forward_gain_stroke = static_cast<S>(m.forward_gain_stroke);
  p.forward_offset = static_cast<S>(m.forward_offset);
  p.forward_offset_stroke = static_cast<S>(m.forward_offset_stroke);
  p.backward_gain = static_cast<S>(m.backward_gain);
  p.backward_gain_stroke = static_cast<S>(m.backward_gain_stroke);
  p.backward_offset = static_cast<S>(m.backward_offset);
  p.backward_offset_stroke = static_cast<S>(m.backward_offset_stroke);
  p.forward_variance = static_cast<S>(m.forward_variance);
  p.backward_variance = static_cast<S>(m.backward_variance);
  p.load_process_variance = static_cast<S>(m.load_process_variance);
  p.friction_variance = static_cast<S>(m.friction_variance);
  p.friction_process_variance = static_cast<S>(m.friction_process_variance);
  p.initial_load = static_cast<S>(m.initial_load);
  p.initial_variance = static_cast<S>(m.initial_variance);
  p.output_offset = static_cast<S>(m.output_offset);
  for (std::size_t j = 0; j < m.stop_thresholds.size(); ++j) {
    const auto i = static_cast<Eigen::Index>(j);
    p.stop_thresholds[i] = static_cast<S>(m.stop_thresholds[j]);
    p.output_shape[i] = static_cast<S>(m.output_shape[j]);
    p.output_shape_per_load[i] = static_cast<S>(m.output_shape_per_load[j]);
  }
  p.sample_time = static_cast<S>(f.state_space.sample_time());
  return p;
}

//! The other way: the settings of a "bidirectional_load_observer" file from `p`
//! (estimation::BidirectionalLoadObserverParameters<S>) and the reference `reference`, field for
//! field beside bidirectional_observer_parameters.
template <typename Parameters, typename Reference>
[[nodiscard]] BidirectionalObserverSettings bidirectional_observer_settings(
    const Parameters& p, const std::optional<Reference>& reference) {
  BidirectionalObserverSettings m;
  m.current_cutoff = static_cast<double>(p.current_cutoff);
  m.velocity_cutoff = static_cast<double>(p.velocity_cutoff);
  m.direction_scale = static_cast<double>(p.direction_scale);
  m.velocity_threshold = static_cast<double>(p.velocity_threshold);
  m.direction_threshold = static_cast<double>(p.direction_threshold);
  m.start_travel = static_cast<double>(p.start_travel);
  m.forward_gain = static_cast<double>(p.forward_gain);
  m.forward_gain_stroke = static_cast<double>(p.forward_gain_stroke);
  m.forward_offset = static_cast<double>(p.forward_offset);
  m.forward_offset_stroke = static_cast<double>(p.forward_offset_stroke);
  m.backward_gain = static_cast<double>(p.backward_gain);
  m.backward_gain_stroke = static_cast<double>(p.backward_gain_stroke);
  m.backward_offset = static_cast<double>(p.backward_offset);
  m.backward_offset_stroke = static_cast<double>(p.backward_offset_stroke);
  m.forward_variance = static_cast<double>(p.forward_variance);
  m.backward_variance = static_cast<double>(p.backward_variance);
  m.load_process_variance = static_cast<double>(p.load_process_variance);
  m.friction_variance = static_cast<double>(p.friction_variance);
  m.friction_process_variance = static_cast<double>(p.friction_process_variance);
  m.initial_load = static_cast<double>(p.initial_load);
  m.initial_variance = static_cast<double>(p.initial_variance);
  m.output_offset = static_cast<double>(p.output_offset);
  for (std::size_t j = 0; j < m.stop_thresholds.size(); ++j) {
    const auto i = static_cast<Eigen::Index>(j);
    m.stop_thresholds[j] = static_cast<double>(p.stop_thresholds[i]);
    m.output_shape[j] = static_cast<double>(p.output_shape[i]);
    m.output_shape_per_load[j] = static_cast<double>(p.output_shape_per_load[i]);
  }
  if (reference) {
    m.command_gain = static_cast<double>(reference->command_gain);
    m.reference_offset = static_cast<double>(reference->reference_offset);
  }
  return m;
}

//! The other way: the settings of a "push_load_observer" file from `p`
//! (estimation::PushLoadObserverParameters<S>; its sample time goes to the file's
//! "sample_time_s"), with the current's offset reference `reference`
//! (estimation::CurrentOffsetReferenceParameters<S>, or none). Field for field beside
//! push_load_observer_parameters, so that a field added to one is seen missing in the other.
template <typename Parameters, typename Reference>
[[nodiscard]] PushLoadObserverSettings push_load_observer_settings(
    const Parameters& p, const std::optional<Reference>& reference) {
  PushLoadObserverSettings m;
  m.current_cutoff = static_cast<double>(p.current_cutoff);
  m.velocity_cutoff = static_cast<double>(p.velocity_cutoff);
  m.direction_scale = static_cast<double>(p.direction_scale);
  m.velocity_threshold = static_cast<double>(p.velocity_threshold);
  m.direction_threshold = static_cast<double>(p.direction_threshold);
  m.push_sign = static_cast<double>(p.push_sign);
  m.current_per_load = static_cast<double>(p.current_per_load);
  m.current_offset = static_cast<double>(p.current_offset);
  m.current_per_velocity = static_cast<double>(p.current_per_velocity);
  m.measurement_variance = static_cast<double>(p.measurement_variance);
  m.process_variance = static_cast<double>(p.process_variance);
  m.initial_load = static_cast<double>(p.initial_load);
  m.initial_variance = static_cast<double>(p.initial_variance);
  m.output_offset = static_cast<double>(p.output_offset);
  m.output_slope = static_cast<double>(p.output_slope);
  m.back_current_per_load = static_cast<double>(p.back_current_per_load);
  m.back_current_offset = static_cast<double>(p.back_current_offset);
  m.back_current_per_velocity = static_cast<double>(p.back_current_per_velocity);
  m.back_variance = static_cast<double>(p.back_variance);
  m.load_per_angle = static_cast<double>(p.load_per_angle);
  if (reference) {
    m.command_gain = static_cast<double>(reference->command_gain);
    m.reference_offset = static_cast<double>(reference->reference_offset);
  }
  return m;
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
