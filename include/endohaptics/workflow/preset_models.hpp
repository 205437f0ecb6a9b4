//! @file
//! The 2016 force models of worksheet appendix C (model/presets_2016.hpp) as model files, by
//! name, for replay and comparison: "yaw2016" (force N) and "pitch2016" (force gf), inputs
//! current (A) and velocity (rad/s). Configuration time: throws endohaptics::Error.
#pragma once

#include <string>
#include <string_view>
#include <vector>
#include "endohaptics/core/separate_compilation.hpp"

#include "endohaptics/core/error.hpp"
#include "endohaptics/files/model_file.hpp"
#include "endohaptics/model/presets_2016.hpp"

namespace endohaptics::workflow {

//! Presets by name: "yaw2016" (appendix C yaw, inputs current A, velocity rad/s, output force N)
//! and "pitch2016" (appendix C pitch, output in gram-force, see docs/models/presets_2016.md).
//! Throws Error for another name.
[[nodiscard]] ENDOHAPTICS_DECL files::ModelFile preset_model(std::string_view name);

}  // namespace endohaptics::workflow

#if !defined(ENDOHAPTICS_SEPARATE_COMPILATION)
#include "endohaptics/workflow/impl/preset_models.ipp"
#endif
