//! @file
//! Settings of the identify workflow (workflow/workflow.hpp): subspace weightings to try and the
//! model order (worksheet 4.2.2), a dead zone per input (4.2.3; half widths in input units), the
//! static-gain baseline, and how x0 is set for the per-file fits.
#pragma once

#include <cstdint>
#include <vector>

#include "endohaptics/identification/subspace.hpp"
#include "endohaptics/workflow/model_comparison.hpp"

namespace endohaptics::workflow {

using namespace endohaptics::identification;  // the workflow composes the identification area

//! Dead zone on one input: none, fitted jointly with the linear block, or of a given half width.
struct DeadzoneSetting {
  //! No dead zone, fitted jointly with the linear block, or fixed at half width `width`.
  enum class Mode : std::uint8_t { none, fit, fixed };
  Mode mode = Mode::none;  //!< what to do on this input
  double width = 0.0;      //!< half width for `fixed`, input units (symmetric: [-w, w])
};

//! Settings of `identify_logs`.
struct WorkflowOptions {
  //! Subspace weightings to try; the one with the highest mean fit over the logs is kept
  //! (worksheet 4.2.2: "the best one is chosen depending on the average fit").
  std::vector<Weighting> candidates{Weighting::moesp};
  bool static_gain = false;  //!< instead: least-squares y = D u + c, no dynamics (baseline)
  int order = 0;             //!< model order; 0: automatic (select_order)
  int max_order = 10;        //!< largest automatic order
  int block_rows = 0;        //!< subspace horizon; 0: automatic
  std::vector<DeadzoneSetting> deadzone;  //!< per input; empty: none
  int deadzone_grid = 21;                 //!< grid points of the dead-zone search
  int deadzone_refine = 15;               //!< golden-section steps of the dead-zone search
  InitialStateMode initial_state = InitialStateMode::estimate;  //!< for the per-file fits
  //! Choose among stable candidates (spectral radius < 1) when there is one: an unstable force
  //! model cannot run open loop in the teleoperation loop.
  bool prefer_stable = true;
};

}  // namespace endohaptics::workflow
