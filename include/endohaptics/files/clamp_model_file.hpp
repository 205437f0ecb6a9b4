//! @file
//! A model file (endohaptics-identify's JSON, files/model_file.hpp) as the force model the bridge
//! runs in a motor's slot (estimation::BridgeJointModel): a Hammerstein-Wiener model of at most 6
//! states, 2 inputs (A, rad/s) and 1 output (N), as estimation::IdentifiedHammersteinWiener (the
//! appendix C yaw type, lower orders embedded), or a joint force model
//! (stall_hold, push_load_observer, bidirectional_load_observer). Refuses what would misbehave at
//! run time: unstable linear blocks, numbers beyond model::max_joint_model_parameter, observers
//! that need the current command. Configuration time: throws endohaptics::Error naming the file.
#pragma once

#include <Eigen/Core>
#include <cmath>
#include <filesystem>
#include <string>
#include <type_traits>
#include <utility>
#include <variant>

#include "endohaptics/core/error.hpp"
#include "endohaptics/core/separate_compilation.hpp"
#include "endohaptics/estimation/bridge_force_models.hpp"
#include "endohaptics/files/model_file.hpp"
#include "endohaptics/model/joint_model_bounds.hpp"
#include "endohaptics/model/state_space.hpp"

namespace endohaptics::files {

//! `file` as the bridge's clamp model; `where` names it in messages ("model file X"). Throws
//! Error when it is of another size, unstable, holds a number beyond 1e6 or refers its current
//! to the command (the sbRIO protocol does not carry it).
[[nodiscard]] ENDOHAPTICS_DECL estimation::BridgeJointModel bridge_joint_model(
    const ModelFile& file, const std::string& where);

//! The model file at `path` (load_model) as the bridge's clamp model (bridge_joint_model).
[[nodiscard]] ENDOHAPTICS_DECL estimation::BridgeJointModel load_bridge_joint_model(
    const std::filesystem::path& path);

}  // namespace endohaptics::files

#if !defined(ENDOHAPTICS_SEPARATE_COMPILATION)
#include "endohaptics/files/impl/clamp_model_file.ipp"
#endif
