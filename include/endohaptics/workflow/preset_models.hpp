//! @file
//! The 2016 force models by name, for replay and comparison: the worksheet's appendix C
//! (model/presets_2016.hpp) "yaw2016" (force N) and "pitch2016" (force gf), and the 2016 code's
//! "clamp2016-as-run" (estimation/clamp_2016_as_run.hpp); the clamp presets replay as the bridge
//! runs them (estimation/clamp_presets.hpp). Inputs current (A), velocity (rad/s), position (rad).
//! Offline: throws endohaptics::Error.
#pragma once

#include <Eigen/Core>
#include <optional>
#include <string>
#include <string_view>
#include <vector>
#include "endohaptics/core/separate_compilation.hpp"

#include "endohaptics/core/error.hpp"
#include "endohaptics/estimation/clamp_presets.hpp"
#include "endohaptics/files/model_file.hpp"
#include "endohaptics/model/presets_2016.hpp"

namespace endohaptics::workflow {

//! Presets by name: "yaw2016" (appendix C yaw, inputs current A, velocity rad/s, output force N),
//! "pitch2016" (appendix C pitch, output in gram-force, see docs/models/presets_2016.md) and
//! "clamp2016-as-run" (the 2016 code's clamp estimator, inputs current A, velocity rad/s,
//! position rad, output force N; its linear block is a placeholder that carries Ts = 0.02 s: it
//! runs only through simulate_clamp_preset). Throws Error for another name.
[[nodiscard]] ENDOHAPTICS_DECL files::ModelFile preset_model(std::string_view name);

//! The clamp preset (estimation/clamp_presets.hpp) a replay of "preset:NAME" runs through the
//! bridge's estimator, or nullopt when NAME is not a clamp preset (pitch2016, a typo).
[[nodiscard]] ENDOHAPTICS_DECL std::optional<estimation::ClampPreset> replayed_clamp_preset(
    std::string_view name);

//! `preset` run on one segment's inputs `u` (columns current A, velocity rad/s and, for
//! clamp2016-as-run, position rad; rows `period` s apart) exactly as the bridge runs it
//! (estimation::run_clamp_preset: the preset's models and settings in BridgeForceEstimator, the
//! log's signals on clamp 1), from its reset state. Force in N per row. Throws Error on a
//! column count the preset does not take, a period the estimator cannot run at, or a
//! non-finite signal or result (naming the sample).
[[nodiscard]] ENDOHAPTICS_DECL Eigen::VectorXd simulate_clamp_preset(estimation::ClampPreset preset,
                                                                     const Eigen::MatrixXd& u,
                                                                     double period);

}  // namespace endohaptics::workflow

#if !defined(ENDOHAPTICS_SEPARATE_COMPILATION)
#include "endohaptics/workflow/impl/preset_models.ipp"
#endif
