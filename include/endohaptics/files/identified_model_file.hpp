//! @file
//! Model files (files/model_file.hpp) from identification results: a SubspaceModel (worksheet
//! 4.2.2) or a HammersteinWienerFit (4.2.3, figure 4.1) with signal names/units and provenance.
//! Kept apart from model_file.hpp so that a program that only loads models (the bridge) does not
//! compile identification. Configuration time: throws Error.
#pragma once

#include <string>
#include <utility>
#include <vector>

#include "endohaptics/files/model_file.hpp"
#include "endohaptics/identification/hammerstein_wiener_fit.hpp"
#include "endohaptics/identification/subspace.hpp"

namespace endohaptics::files {

//! An identified SubspaceModel with signal names/units and provenance: its state_space (x0 = the
//! first data set's initial state), method (the weighting when empty), order and block rows from
//! the model, date today if empty. Throws Error as make_model_file for a StateSpace.
[[nodiscard]] inline ModelFile make_model_file(const identification::SubspaceModel& m,
                                               std::vector<SignalInfo> inputs,
                                               std::vector<SignalInfo> outputs,
                                               ModelProvenance provenance = {}) {
  if (provenance.method.empty()) provenance.method = identification::to_string(m.weighting);
  provenance.block_rows = m.block_rows;
  ModelFile f =
      make_model_file(m.state_space, std::move(inputs), std::move(outputs), std::move(provenance));
  f.provenance.order = m.order;
  return f;
}

//! A fitted Hammerstein-Wiener model (maps included) with names, units and provenance (the fit
//! per output when `provenance.fit_percent` is empty). Throws Error as the SubspaceModel form,
//! or when the map counts differ from the model's inputs and outputs.
[[nodiscard]] inline ModelFile make_model_file(const identification::HammersteinWienerFit& hw,
                                               std::vector<SignalInfo> inputs,
                                               std::vector<SignalInfo> outputs,
                                               ModelProvenance provenance = {}) {
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
