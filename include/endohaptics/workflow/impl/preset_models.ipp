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
  if (name == "clamp2016-as-run") {
    p.method =
        "the 2016 code as it ran (filipmrc/endohap src/Endowrist.cc, src/Kalman.cc), "
        "estimation::Clamp2016AsRun; run by simulate_clamp_preset, the linear block a placeholder";
    using Placeholder = model::StateSpace<1, 3, 1>;
    return files::make_model_file(
        Placeholder(Placeholder::MatrixA::Zero(), Placeholder::MatrixB::Zero(),
                    Placeholder::MatrixC::Zero(), Placeholder::MatrixD::Zero(),
                    model::sample_time_2016),
        {{"current", "A"}, {"velocity", "rad/s"}, {"position", "rad"}}, {{"force", "N"}}, p);
  }
  ENDOHAPTICS_THROW(Error("unknown preset '" + std::string(name) +
                          "' (valid: yaw2016, pitch2016, clamp2016-as-run)"));
}

ENDOHAPTICS_DECL std::optional<estimation::ClampPreset> replayed_clamp_preset(
    std::string_view name) {
  if (name == "yaw2016") return estimation::ClampPreset::yaw2016;
  if (name == "clamp2016-as-run") return estimation::ClampPreset::clamp2016_as_run;
  return std::nullopt;
}

ENDOHAPTICS_DECL Eigen::VectorXd simulate_clamp_preset(estimation::ClampPreset preset,
                                                       const Eigen::MatrixXd& u, double period) {
  const Eigen::Index needed = preset == estimation::ClampPreset::clamp2016_as_run ? 3 : 2;
  if (u.cols() != needed) {
    ENDOHAPTICS_THROW(Error("preset:" + std::string(estimation::to_string(preset)) + " takes " +
                            std::to_string(needed) + " input columns, got " +
                            std::to_string(u.cols())));
  }
  Eigen::VectorXd y(u.rows());
  const NumericStatus status = estimation::run_clamp_preset(
      preset, period,
      [&](Eigen::Index k) {
        return estimation::JointSignals<double>{needed == 3 ? u(k, 2) : 0.0, u(k, 1), u(k, 0), 0.0};
      },
      y);
  if (status != NumericStatus::ok) {
    Eigen::Index k = 0;  // the first sample whose step failed: the first non-finite one
    while (k < u.rows() && u.row(k).allFinite()) ++k;
    ENDOHAPTICS_THROW(Error("preset:" + std::string(estimation::to_string(preset)) + ": " +
                            std::string(to_string(status)) +
                            (k < u.rows() ? " at sample " + std::to_string(k) : std::string())));
  }
  return y;
}

}  // namespace endohaptics::workflow
