//! @file
//! Function bodies of files/identified_model_file.hpp: included at its end (header-only, the
//! default), or compiled once with ENDOHAPTICS_SEPARATE_COMPILATION
//! (core/separate_compilation.hpp).
#pragma once

#include "endohaptics/files/identified_model_file.hpp"

namespace endohaptics::files {

ENDOHAPTICS_DECL ModelFile make_model_file(const identification::SubspaceModel& m,
                                           std::vector<SignalInfo> inputs,
                                           std::vector<SignalInfo> outputs,
                                           ModelProvenance provenance) {
  if (provenance.method.empty()) provenance.method = identification::to_string(m.weighting);
  provenance.block_rows = m.block_rows;
  ModelFile f =
      make_model_file(m.state_space, std::move(inputs), std::move(outputs), std::move(provenance));
  f.provenance.order = m.order;
  return f;
}

ENDOHAPTICS_DECL ModelFile make_model_file(const identification::HammersteinWienerFit& hw,
                                           std::vector<SignalInfo> inputs,
                                           std::vector<SignalInfo> outputs,
                                           ModelProvenance provenance) {
  if (provenance.fit_percent.empty()) {
    provenance.fit_percent.assign(hw.fit.data(), hw.fit.data() + hw.fit.size());
  }
  ModelFile f =
      make_model_file(hw.linear, std::move(inputs), std::move(outputs), std::move(provenance));
  f.input_nonlinearity = hw.input;
  f.output_nonlinearity = hw.output;
  detail::model_file::validate(f, "make_model_file");
  return f;
}

}  // namespace endohaptics::files
