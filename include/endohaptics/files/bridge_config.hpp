//! @file
//! The bridge's configuration file (JSON) <-> the library's configuration structs: mapping
//! (kinematics::CylindricalMapperConfig), safety and receive timeout (teleop::TeleopLoopConfig),
//! force estimator settings and the force models (a clamp model file, or the folder of model sets
//! and the instrument whose set runs: files/model_set_file.hpp), scripted operator
//! (sim::OperatorScript). Strict: every key optional, defaults are the library's; unknown or
//! duplicate keys, wrong types, non-integral or out-of-range values are errors naming the file, the
//! key and the range.
#pragma once

#include <Eigen/Core>
#include <array>
#include <chrono>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <filesystem>
#include <fstream>
#include <limits>
#include <numbers>
#include <optional>
#include <string>
#include <string_view>
#include <type_traits>
#include <variant>
#include <vector>

#include "endohaptics/core/error.hpp"
#include "endohaptics/core/parameter.hpp"
#include "endohaptics/core/separate_compilation.hpp"
#include "endohaptics/estimation/bridge_force_models.hpp"
#include "endohaptics/estimation/clamp_presets.hpp"
#include "endohaptics/estimation/force_estimator.hpp"
#include "endohaptics/files/clamp_model_file.hpp"
#include "endohaptics/files/model_file.hpp"
#include "endohaptics/files/model_set_file.hpp"
#include "endohaptics/kinematics/cylindrical_mapper.hpp"
#include "endohaptics/model/joint_model_bounds.hpp"
#include "endohaptics/model/state_space.hpp"
#include "endohaptics/sim/scripted_operator.hpp"
#include "endohaptics/teleop/safety.hpp"
#include "endohaptics/teleop/teleop_loop.hpp"

namespace endohaptics::files {

//! Everything the bridge's --config file sets. Keys (docs/rig.md, "The configuration file"):
//! "mapping" -> mapping, "safety" -> loop.safety, "loop.receive_timeout" (s) ->
//! loop.receive_timeout, "estimator" -> estimator, clamp_model, model_sets and instrument,
//! "operator" -> operator_script.
struct BridgeConfig {
  kinematics::CylindricalMapperConfig<double> mapping{};  //!< eqs. 5.8/5.9
  //! Safety and receive timeout; `period` is not in the file (the bridge's --rate sets it).
  teleop::TeleopLoopConfig loop{};
  estimation::ForceEstimatorSettings<double> estimator{};  //!< friction levels, signs, limits
  //! "estimator.clamp_model": an identified model file (endohaptics-identify) for both clamps:
  //! Hammerstein-Wiener (6 states, 2 inputs, 1 output), "stall_hold", "push_load_observer" or
  //! "bidirectional_load_observer", resolved against the configuration file's folder; or a clamp
  //! preset, "preset:yaw2016" or "preset:clamp2016-as-run" (estimation/clamp_presets.hpp); empty:
  //! the 2016 appendix C yaw model.
  std::filesystem::path clamp_model;
  //! "estimator.model_sets": a folder of model sets, one per instrument (`NAME.json` or
  //! `NAME/`, files/model_set_file.hpp), resolved against the configuration file's folder.
  std::filesystem::path model_sets;
  //! "estimator.instrument" (or the bridge's --instrument): the instrument whose set in
  //! model_sets the bridge runs; not with clamp_model.
  std::string instrument;
  sim::OperatorScript operator_script{};  //!< the scripted operator of `--device sim`
};

//! Largest configuration file `load_bridge_config` reads, bytes (a complete one is < 2 kB).
inline constexpr std::size_t bridge_config_max_bytes = std::size_t{1} << 20;
//! Deepest nesting of arrays and objects accepted (the schema itself needs 3).
inline constexpr int bridge_config_max_depth = 64;

//! The force models `config` names, with the line the bridge logs: the instrument's model set
//! (estimator.instrument in estimator.model_sets, files/model_set_file.hpp; refused when it misses
//! a motor the mapping feeds back), else estimator.clamp_model for both clamps (a model file or
//! "preset:NAME", estimation/clamp_presets.hpp), else the 2016 models. Refuses an instrument
//! together with a clamp_model, and an instrument without model_sets. Throws Error.
[[nodiscard]] ENDOHAPTICS_DECL BridgeModelSet
bridge_config_force_models(const BridgeConfig& config);

//! Checks `config` as the bridge will use it: every field in its schema range, then the
//! library's own checks (TeleopLoopConfig, CylindricalMapper, OperatorScript, and a
//! ForceEstimator built with the clamp model file). Throws Error "<source>: <key>: ...".
ENDOHAPTICS_DECL void validate_bridge_config(const BridgeConfig& config,
                                             std::string_view source = "bridge configuration");

//! Reads a bridge configuration from JSON `text` over the defaults, then validates it
//! (validate_bridge_config). `source` names the text in messages; a relative
//! estimator.clamp_model or model_sets is resolved against `base_dir` (empty: left relative).
//! Throws Error naming the source, the key and the allowed range or values.
[[nodiscard]] ENDOHAPTICS_DECL BridgeConfig
parse_bridge_config(std::string_view text, std::string_view source = "<string>",
                    const std::filesystem::path& base_dir = {});

//! Reads the bridge configuration file `path` (a regular file of at most
//! bridge_config_max_bytes: a FIFO or device is refused without blocking, files/json_text.hpp) as
//! parse_bridge_config, with the file's name in messages and relative model files resolved
//! against its folder.
[[nodiscard]] ENDOHAPTICS_DECL BridgeConfig load_bridge_config(const std::filesystem::path& path);

//! The configuration as JSON text in the file's format (every key; clamp_model, model_sets and
//! instrument when set):
//! parse_bridge_config reads it back to the same values.
[[nodiscard]] ENDOHAPTICS_DECL std::string bridge_config_json(const BridgeConfig& config,
                                                              int indent = 2);

}  // namespace endohaptics::files

#if !defined(ENDOHAPTICS_SEPARATE_COMPILATION)
#include "endohaptics/files/impl/bridge_config.ipp"
#endif
