//! @file
//! Model files (files/model_file.hpp) from identification results: a SubspaceModel (worksheet
//! 4.2.2) or a HammersteinWienerFit (4.2.3, figure 4.1) with signal names/units and provenance.
//! Kept apart from model_file.hpp so that a program that only loads models (the bridge) does not
//! compile identification. Configuration time: throws Error.
#pragma once

#include <string>
#include <utility>
#include <vector>
#include "endohaptics/core/separate_compilation.hpp"

#include "endohaptics/files/model_file.hpp"
#include "endohaptics/identification/hammerstein_wiener_fit.hpp"
#include "endohaptics/identification/subspace.hpp"

namespace endohaptics::files {

//! An identified SubspaceModel with signal names/units and provenance: its state_space (x0 = the
//! first data set's initial state), method (the weighting when empty), order and block rows from
//! the model, date today if empty. Throws Error as make_model_file for a StateSpace.
[[nodiscard]] ENDOHAPTICS_DECL ModelFile make_model_file(const identification::SubspaceModel& m,
                                                         std::vector<SignalInfo> inputs,
                                                         std::vector<SignalInfo> outputs,
                                                         ModelProvenance provenance = {});

//! A fitted Hammerstein-Wiener model (maps included) with names, units and provenance (the fit
//! per output when `provenance.fit_percent` is empty). Throws Error as the SubspaceModel form,
//! or when the map counts differ from the model's inputs and outputs.
[[nodiscard]] ENDOHAPTICS_DECL ModelFile
make_model_file(const identification::HammersteinWienerFit& hw, std::vector<SignalInfo> inputs,
                std::vector<SignalInfo> outputs, ModelProvenance provenance = {});

}  // namespace endohaptics::files

#if !defined(ENDOHAPTICS_SEPARATE_COMPILATION)
#include "endohaptics/files/impl/identified_model_file.ipp"
#endif
