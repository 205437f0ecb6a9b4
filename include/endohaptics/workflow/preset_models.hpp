//! @file
//! The 2016 force models of worksheet appendix C (model/presets_2016.hpp) as model files, by
//! name, for replay and comparison: "yaw2016" (force N) and "pitch2016" (force gf), inputs
//! current (A) and velocity (rad/s). Configuration time: throws endohaptics::Error.
#pragma once

#include <string>
#include <string_view>
#include <vector>

#include "endohaptics/core/error.hpp"
#include "endohaptics/files/model_file.hpp"
#include "endohaptics/model/presets_2016.hpp"

namespace endohaptics::workflow {

//! Presets by name: "yaw2016" (appendix C yaw, inputs current A, velocity rad/s, output force N)
//! and "pitch2016" (appendix C pitch, output in gram-force, see docs/models/presets_2016.md).
//! Throws Error for another name.
[[nodiscard]] inline files::ModelFile preset_model(std::string_view name) {
  const std::vector<files::SignalInfo> inputs{{"current", "A"}, {"velocity", "rad/s"}};
  files::ModelProvenance p;
  p.date = "2016";
  if (name == "yaw2016") {
    p.method = "worksheet appendix C (yaw, eqs. C.1-C.3)";
    return files::make_model_file(model::yaw_force_2016(), inputs, {{"force", "N"}}, p);
  }
  if (name == "pitch2016") {
    p.method = "worksheet appendix C (pitch, eqs. C.4-C.6)";
    return files::make_model_file(model::pitch_force_2016(), inputs, {{"force", "gf"}}, p);
  }
  ENDOHAPTICS_THROW(
      Error("unknown preset '" + std::string(name) + "' (valid: yaw2016, pitch2016)"));
}

}  // namespace endohaptics::workflow
