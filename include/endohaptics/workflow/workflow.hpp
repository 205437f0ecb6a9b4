//! @file
//! The identification workflow of worksheet 4.2 as endohaptics-identify runs it: fit candidates
//! on logs prepared for fitting (workflow/prepared_log.hpp, 4.2.1; subspace 4.2.2, input dead
//! zones 4.2.3, or the static gain baseline), score each causally on the same logs prepared for
//! scoring (workflow/model_comparison.hpp), refuse unstable and near-integrating ones
//! (time constant in s) and keep the best. Includes the whole workflow area.
//! Configuration time: allocates, throws endohaptics::Error. See docs/identification_results.md.
#pragma once

#include <Eigen/Core>
#include <algorithm>
#include <array>
#include <cmath>
#include <cstddef>
#include <cstdio>
#include <limits>
#include <optional>
#include <span>
#include <string>
#include <utility>
#include <vector>
#include "endohaptics/core/separate_compilation.hpp"

#include "endohaptics/core/error.hpp"
#include "endohaptics/files/identified_model_file.hpp"
#include "endohaptics/files/model_file.hpp"
#include "endohaptics/identification/hammerstein_wiener_fit.hpp"
#include "endohaptics/identification/subspace.hpp"
#include "endohaptics/model/static_map.hpp"
#include "endohaptics/workflow/error_context.hpp"
#include "endohaptics/workflow/joint_models.hpp"
#include "endohaptics/workflow/method.hpp"
#include "endohaptics/workflow/model_comparison.hpp"
#include "endohaptics/workflow/prepared_log.hpp"
#include "endohaptics/workflow/static_gain_fit.hpp"
#include "endohaptics/workflow/workflow_options.hpp"
// Not used here: the rest of the workflow area, so that this header still gives all of it.
#include "endohaptics/workflow/format_defaults.hpp"
#include "endohaptics/workflow/option_parsing.hpp"
#include "endohaptics/workflow/preprocessing.hpp"
#include "endohaptics/workflow/preset_models.hpp"

namespace endohaptics::workflow {

using namespace endohaptics::identification;  // the workflow composes the identification area

//! One candidate model and its per-file scores on the identification logs.
struct CandidateModel {
  std::string method;                   //!< display name: to_string(kind) (+ " + dead zone")
  Method kind = Method::moesp;          //!< the fit that made it: a subspace method or static_gain
  files::ModelFile model;               //!< with names, units, provenance (notes empty)
  SubspaceModel linear;                 //!< the identified linear block (singular values, ...)
  std::vector<FileComparison> files{};  //!< per identification log, scored as options.scoring
  double mean_fit = 0.0;                //!< mean over files and outputs, %
  double spectral_radius = 0.0;         //!< max |eig(A)|
  double time_constant = 0.0;           //!< s, of the slowest mode (Inf: unstable or integrating)
  std::string refused{};                //!< why it may not be chosen; empty: admissible
  bool order_searched = false;          //!< its order was chosen by the order search
};

//! One point of the order search: the best method and dead zone refitted at `order`.
struct OrderTrial {
  int order = 0;               //!< model order
  double mean_fit = 0.0;       //!< causal score, %
  double spectral_radius = 0;  //!< max |eig(A)|
  std::string refused{};       //!< why refused; empty: admissible
};

//! All candidates tried and the index of the best.
struct WorkflowResult {
  std::vector<CandidateModel> candidates;  //!< the best of each method, in the order tried
  std::size_t best = 0;                    //!< index of the chosen one (best_candidate)
  std::vector<std::string> failures;       //!< "method: message" of candidates that failed
  std::vector<OrderTrial> order_search{};  //!< the order search on the best method, if run
  int evaluations = 0;                     //!< models fitted and scored

  //! The candidate at index `best`; throws std::out_of_range if `best` is out of range.
  [[nodiscard]] const CandidateModel& chosen() const { return candidates.at(best); }
};

//! Slowest time constant of `linear`, s: -Ts / ln(spectral radius); +Inf for a spectral radius
//! >= 1; 0 for a static model (no states, or spectral radius 0).
[[nodiscard]] ENDOHAPTICS_DECL double slowest_time_constant(
    const model::DynamicStateSpace<>& linear);

//! The slowest time constant a candidate may have and what sets it.
struct TimeConstantLimit {
  double seconds = std::numeric_limits<double>::infinity();  //!< s; infinity: none
  //! What sets it, for messages: "" (the number given), or "the longest segment, N samples of
  //! Ts s: ..." when the logs bound it more tightly.
  std::string source{};
};

//! The limit identify_logs applies: `max_time_constant` (s), or the duration of the longest
//! segment of `fit_logs` (its samples times the sample time) when that is shorter. A mode slower
//! than the longest stretch of data decays by less than 1/e within it: the data cannot tell it
//! from a drift set by the unknown initial state, so it is not identifiable from them
//! (docs/identification_results.md).
[[nodiscard]] ENDOHAPTICS_DECL TimeConstantLimit
time_constant_limit(double max_time_constant, const std::vector<PreparedLog>& fit_logs);

//! Why a candidate must not be chosen, or "" when it may: unstable (spectral radius >= 1) or
//! near-integrating (slowest time constant > limit.seconds; the message names limit.source).
//! The static baseline (kind static_gain, A = I, B = 0: a constant, not a mode) is exempt.
[[nodiscard]] ENDOHAPTICS_DECL std::string refusal(const CandidateModel& c,
                                                   const TimeConstantLimit& limit);

//! `refusal` with a limit of `max_time_constant` s from no stated source.
[[nodiscard]] ENDOHAPTICS_DECL std::string refusal(const CandidateModel& c,
                                                   double max_time_constant);

//! Index of the admissible candidate (refused empty) with the highest mean fit. Throws Error
//! listing why each was refused when none is admissible, or when `candidates` is empty.
[[nodiscard]] ENDOHAPTICS_DECL std::size_t best_candidate(
    const std::vector<CandidateModel>& candidates);

namespace detail {

//! Causal mean fit used to rank candidates: -Inf for a diverging or refused one.
ENDOHAPTICS_DECL double ranking_score(const CandidateModel& c);

}  // namespace detail

//! Identifies candidates from all segments of all `fit_logs` (one x0 per segment): per subspace
//! method, the dead zones of options.deadzone (`fit`: a grid over [0, half the largest |u|], then
//! golden-section steps, each width a refit), each scored on `score_logs` (the same files
//! prepared for scoring, same order) with options.scoring; unstable and near-integrating models
//! (time_constant_limit(options.max_time_constant, fit_logs)) are refused. With an automatic order,
//! every order 1..max_order is then tried for the best subspace method and dead zones; the smallest
//! within options.order_tolerance of the best replaces it. With options.static_gain the static
//! baseline (same dead-zone search) is one more candidate. Keeps the best admissible causal score.
//! With several candidates a failing one is recorded in `failures` and skipped. Throws Error on bad
//! options or data, when every candidate failed or was refused, or when the log lists differ in
//! length. The block-Hankel factor of each dead-zone setting is computed once and reused by the
//! order search (it does not depend on the order). `factor` (optional): the Hankel factor of all
//! segments of `fit_logs`, in order, mapped by the dead zones options.deadzone starts from (fixed
//! widths, 0 for fitted ones), e.g. `combine` of per-file factors: the fits with those dead
//! zones use it instead of a pass over the data (choose_family's folds).
[[nodiscard]] ENDOHAPTICS_DECL WorkflowResult identify_logs(
    const std::vector<PreparedLog>& fit_logs, const std::vector<PreparedLog>& score_logs,
    const std::vector<files::SignalInfo>& inputs, const std::vector<files::SignalInfo>& outputs,
    const WorkflowOptions& options, const HankelFactor* factor = nullptr);

//! What `choose_family` chose and why.
struct ModelChoice {
  files::ModelFile model;               //!< the chosen family fitted on every training file
  std::string family{};                 //!< its name: the subspace candidate's method or the kind
  std::vector<FamilyScore> families{};  //!< every family with its inner cross-validation score
  std::size_t best = 0;                 //!< index of the chosen family in `families`
  std::vector<std::vector<std::size_t>> folds{};  //!< training files held out per inner fold
  std::vector<FileComparison> files{};  //!< the chosen model on each training file, causal
  std::string joint_summary{};          //!< the fitted values when a joint model was chosen
  //! Joint-model constant searches run: choose_joint_constants once per joint family with
  //! constants to choose (on all training files), plus JointModelFit::constant_searches of every
  //! fit (0: the inner folds and the final fit are given those constants).
  std::size_t constant_searches = 0;
};

//! Chooses the model family by the causal score on the training files only (never a held-out
//! file): the subspace workflow's chosen candidate (`subspace`; null: none) and one family per
//! kind of `joint_kinds`. With two or more families and two or more files, an inner
//! cross-validation (inner_folds: leave-one-file-out up to 5 files, else 5 folds) fits each
//! family on the other folds and scores it causally on the held-out one; the highest mean fit
//! over the folds wins (a family that fails or is refused on a fold loses). The subspace family
//! is refitted in each fold with the structure chosen on all training files (method, order, dead
//! zones fixed: cheaper, and if anything in its favour). So is a joint family: its constants that
//! no physics fixes (the stall-hold's threshold and time constants, the bidirectional observer's
//! noise rule and front end) are chosen once, by the blocked cross-validation inside the fit on
//! all training files (choose_joint_constants), and each fold refits only its least-squares parts
//! with them held (fit_joint_model with constants); the final fit on every training file uses the
//! same constants, so the chosen model is the one fit_joint_model makes on them. The held-out
//! files of an outer evaluation are never among the training files, so they choose nothing.
//! Held so, the constants have seen each fold's held-out files (a leak in the joint family's
//! favour, as in the subspace family's); options.nested_joint_constants searches them again in
//! each fold instead (the old, slower way). Otherwise the only family is chosen.
//! `fit_logs`/`score_logs`: the subspace grid, prepared for fitting and for scoring; `joint_logs`:
//! the joint models' grid, prepared for scoring (all three: the same files, same order). The
//! chosen family is then fitted on every training file. Throws Error when nothing can be fitted.
//! The subspace family's folds reuse one block-Hankel factor per training file (`combine`d per
//! fold) instead of a pass over the fold's data.
[[nodiscard]] ENDOHAPTICS_DECL ModelChoice choose_family(
    const WorkflowResult* subspace, const std::vector<files::ModelKind>& joint_kinds,
    const std::vector<PreparedLog>& fit_logs, const std::vector<PreparedLog>& score_logs,
    const std::vector<PreparedLog>& joint_logs, const std::vector<files::SignalInfo>& inputs,
    const std::vector<files::SignalInfo>& outputs, const WorkflowOptions& options);

}  // namespace endohaptics::workflow

#if !defined(ENDOHAPTICS_SEPARATE_COMPILATION)
#include "endohaptics/workflow/impl/workflow.ipp"
#endif
