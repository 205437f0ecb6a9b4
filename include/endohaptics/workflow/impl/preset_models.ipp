//! @file
//! Function bodies of workflow/preset_models.hpp: included at its end (header-only, the default),
//! or compiled once with ENDOHAPTICS_SEPARATE_COMPILATION (core/separate_compilation.hpp).
#pragma once

#include "endohaptics/workflow/preset_models.hpp"

namespace endohaptics::workflow {

ENDOHAPTICS_DECL files::ModelFile preset_model(std::string_view name) {
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
