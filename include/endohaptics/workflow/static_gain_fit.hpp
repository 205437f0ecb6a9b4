//! @file
//! The static-gain baseline of the identify workflow: y = D u + c by least squares over every
//! segment (no dynamics), as a SubspaceModel with one constant state per output (A = I, B = 0,
//! C = I, x0 = c). Signals keep their units. Configuration time: throws endohaptics::Error.
#pragma once

#include <Eigen/Core>
#include <Eigen/QR>
#include <span>
#include <string>
#include <utility>
#include "endohaptics/core/separate_compilation.hpp"

#include "endohaptics/identification/subspace.hpp"
#include "endohaptics/model/state_space.hpp"
#include "endohaptics/workflow/error_context.hpp"

namespace endohaptics::workflow {

using namespace endohaptics::identification;  // the workflow composes the identification area

//! y = D u + c by least squares over every segment, as a model file with one constant state per
//! output (A = I, B = 0, C = I, x0 = c). Throws Error when the regression is singular.
[[nodiscard]] ENDOHAPTICS_DECL SubspaceModel fit_static_gain(std::span<const DataSet> data,
                                                             double sample_time);

}  // namespace endohaptics::workflow

#if !defined(ENDOHAPTICS_SEPARATE_COMPILATION)
#include "endohaptics/workflow/impl/static_gain_fit.ipp"
#endif
