//! @file
//! One model set per instrument: the force model of each motor of one EndoWrist (roll, pitch,
//! clamp1, clamp2), as a set file (JSON, "endohaptics model set", format_version 1) or a directory
//! of `<motor>.json` model files, chosen by instrument name from a folder of sets, and made into
//! the models the bridge runs (estimation::BridgeForceModels). A set must cover every motor whose
//! stylus channel has force feedback (mapping.force_scale != 0); a motor without a model and
//! without feedback runs its 2016 preset. Every motor takes any kind files/clamp_model_file.hpp
//! runs (an identified model of that motor), or its preset: "preset:yaw2016" /
//! "preset:clamp2016-as-run" for a clamp, "preset:roll2016" / "preset:pitch2016" for roll and
//! pitch.
//! Configuration time: throws endohaptics::Error naming the file and the field.
#pragma once

#include <array>
#include <cstddef>
#include <filesystem>
#include <string>
#include <string_view>

#include "endohaptics/core/error.hpp"
#include "endohaptics/core/separate_compilation.hpp"
#include "endohaptics/estimation/bridge_force_models.hpp"
#include "endohaptics/estimation/clamp_2016_as_run.hpp"
#include "endohaptics/estimation/force_models_2016.hpp"
#include "endohaptics/files/clamp_model_file.hpp"
#include "endohaptics/files/model_file.hpp"
#include "endohaptics/kinematics/cylindrical_mapper.hpp"
#include "endohaptics/protocol/motor_order.hpp"

namespace endohaptics::files {

//! The "format" of a set file.
inline constexpr std::string_view model_set_format = "endohaptics model set";
//! The "format_version" this library reads and writes.
inline constexpr int model_set_format_version = 1;
//! The set file a model-set directory may hold (else its `<motor>.json` files are the set).
inline constexpr std::string_view model_set_file_name = "model_set.json";
//! Largest set file read, bytes (one names four files).
inline constexpr std::size_t model_set_max_bytes = std::size_t{1} << 16;

//! One instrument's model set as read: each motor's model file (resolved against the set's
//! folder) or "preset:NAME", by protocol::Motor index; empty: the set gives none.
struct ModelSet {
  std::string instrument;               //!< the instrument's name
  std::filesystem::path source;         //!< the set file or the directory read
  std::array<std::string, 4> models{};  //!< per Motor: a model file path, "preset:NAME" or ""

  //! The entry of `motor`.
  [[nodiscard]] const std::string& model(protocol::Motor motor) const noexcept {
    return models[static_cast<std::size_t>(motor)];
  }
};

//! The motors in the order sets list them (and logs name them): clamp1, clamp2, roll, pitch.
inline constexpr std::array<protocol::Motor, 4> model_set_motors = {
    protocol::Motor::clamp1, protocol::Motor::clamp2, protocol::Motor::roll,
    protocol::Motor::pitch};

//! Reads a set file's JSON `text`: {"format": "endohaptics model set", "format_version": 1,
//! "instrument": NAME, "models": {MOTOR: FILE or "preset:NAME", ...}} (MOTOR: roll, pitch,
//! clamp1, clamp2; files relative to `base_dir`). Unknown keys and motors, a missing field and a
//! value of the wrong type are refused. Throws Error "<source>: <field>: ...".
[[nodiscard]] ENDOHAPTICS_DECL ModelSet parse_model_set(std::string_view text,
                                                        const std::string& source,
                                                        const std::filesystem::path& base_dir = {});

//! The model set at `path`: a set file (parse_model_set, files relative to its folder), or a
//! directory holding model_set_file_name (read as a set file) or else `<motor>.json` model files
//! (the instrument's name: the directory's). Throws Error naming the path.
[[nodiscard]] ENDOHAPTICS_DECL ModelSet load_model_set(const std::filesystem::path& path);

//! The set of `instrument` in the folder `folder`: `folder/<instrument>.json` or
//! `folder/<instrument>/` (not both), its "instrument" the same name. The name is a plain file
//! name (letters, digits, '.', '_', '-'; not starting with '.'). Throws Error naming the folder.
[[nodiscard]] ENDOHAPTICS_DECL ModelSet
load_instrument_model_set(const std::filesystem::path& folder, const std::string& instrument);

//! Which motors have force feedback in `mapping` (by Motor index): the clamps render through
//! channel 0 (force_scale[0]), roll through 1, pitch through 2; a scale of 0 renders nothing.
[[nodiscard]] inline std::array<bool, 4> force_feedback_motors(
    const kinematics::CylindricalMapperConfig<double>& mapping) noexcept {
  std::array<bool, 4> fed{};
  fed[static_cast<std::size_t>(protocol::Motor::clamp1)] = mapping.force_scale[0] != 0.0;
  fed[static_cast<std::size_t>(protocol::Motor::clamp2)] = mapping.force_scale[0] != 0.0;
  fed[static_cast<std::size_t>(protocol::Motor::roll)] = mapping.force_scale[1] != 0.0;
  fed[static_cast<std::size_t>(protocol::Motor::pitch)] = mapping.force_scale[2] != 0.0;
  return fed;
}

//! A model set made into the models the bridge runs, with the line the bridge logs.
struct BridgeModelSet {
  estimation::BridgeForceModels models;  //!< the force models
  std::string description;  //!< e.g. "instrument A (sets/A.json): clamp1 stall_hold (...), ..."
};

//! The models of `set` (its motors fed back per `fed_back`, force_feedback_motors): a motor's
//! model file as bridge_joint_model runs it (any motor: an identified model gives the force it was
//! fitted to), or its preset (a clamp: preset:yaw2016 or preset:clamp2016-as-run; roll and pitch:
//! preset:roll2016, preset:pitch2016). Refuses a set that misses a fed-back motor (naming them
//! all) and an unknown preset. Throws Error "<set>: models.<motor>: ...".
[[nodiscard]] ENDOHAPTICS_DECL BridgeModelSet bridge_model_set(const ModelSet& set,
                                                               const std::array<bool, 4>& fed_back);

}  // namespace endohaptics::files

#if !defined(ENDOHAPTICS_SEPARATE_COMPILATION)
#include "endohaptics/files/impl/model_set_file.ipp"
#endif
