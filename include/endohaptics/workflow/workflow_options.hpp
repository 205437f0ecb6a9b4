//! @file
//! Settings of the identify workflow (workflow/workflow.hpp): subspace weightings to try and the
//! model order (worksheet 4.2.2), a dead zone per input (4.2.3; half widths in input units), the
//! static-gain baseline, how candidates are scored (causally: workflow/model_comparison.hpp) and
//! which are refused (unstable or near-integrating: slowest time constant in s).
#pragma once

#include <cstdint>
#include <functional>
#include <limits>
#include <string_view>
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
  //! Also (or, with no `candidates`, only) the baseline: least-squares y = D u + c, no dynamics,
  //! a candidate like the others (it is never refused: its constant is not a mode).
  bool static_gain = false;
  int order = 0;                          //!< model order; 0: automatic (select_order)
  int max_order = 10;                     //!< largest automatic order
  int block_rows = 0;                     //!< subspace horizon; 0: automatic
  std::vector<DeadzoneSetting> deadzone;  //!< per input; empty: none
  int deadzone_grid = 11;   //!< grid points of the dead-zone search, 0 .. half max |u|
  int deadzone_refine = 6;  //!< golden-section steps around the best grid point
  //! With order 0 (automatic): also try every order 1..max_order for the best method and dead
  //! zone and keep the best causal score (else: select_order's choice only).
  bool search_order = true;
  //! The order search keeps the smallest order whose causal score is within this many
  //! percentage points of the best order's (a higher order must earn its states).
  double order_tolerance = 0.5;
  //! How every candidate is scored on the scoring logs: the choice of method, order and dead
  //! zone uses this score (causal by default: steady-state x0, warm-up excluded).
  ScoringOptions scoring{};
  //! Candidates whose slowest mode has a time constant -Ts / ln(spectral radius) above this (s)
  //! are refused as near-integrating: their level would come from the initial state, not from the
  //! inputs. Infinity: no absolute limit (generic records); the force-model formats set 2 s, twice
  //! the longest warm-up (FormatDefaults::max_time_constant). Whatever it says, a mode slower than
  //! the longest segment of the logs is refused (time_constant_limit), and so is every unstable
  //! candidate (spectral radius >= 1).
  double max_time_constant = std::numeric_limits<double>::infinity();
  //! choose_family: search a joint family's constants (fit_joint_model's blocked cross-validation)
  //! again inside each inner fold, on the fold's training files only, instead of once on all
  //! training files and held in the folds. Nested, the family scores carry no leak from a fold's
  //! held-out files into its constants, at the cost of one search per fold (the UMN 70-run
  //! default search 2.5 min instead of under 1); the model chosen is fitted the same way either
  //! way, only the family scores (so possibly the family) differ.
  bool nested_joint_constants = false;
  //! Called with one line (no newline) after each model fitted and scored by identify_logs and
  //! after each fold of choose_family's cross-validation, for long runs (the UMN search fits
  //! dozens of models); empty: silent. A program prints it, e.g. to stderr.
  std::function<void(std::string_view)> progress{};
};

}  // namespace endohaptics::workflow
