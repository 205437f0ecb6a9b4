//! @file
//! endohaptics-identify as a function: a request (the command line's settings as a plain struct,
//! each format-defaulted one optional) -> a report holding the resolved settings, the prepared
//! logs, the subspace workflow's candidates, the family choice and the chosen model with its
//! provenance notes (worksheet 4.2; workflow/workflow.hpp). Sample times in s, cut-offs in Hz.
//! Configuration time: allocates, throws endohaptics::Error.
#pragma once

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <functional>
#include <optional>
#include <string>
#include <string_view>
#include <vector>
#include "endohaptics/core/separate_compilation.hpp"

#include "endohaptics/files/model_file.hpp"
#include "endohaptics/model/stop_operators.hpp"
#include "endohaptics/workflow/method.hpp"
#include "endohaptics/workflow/model_comparison.hpp"
#include "endohaptics/workflow/prepared_log.hpp"
#include "endohaptics/workflow/preprocessing.hpp"
#include "endohaptics/workflow/workflow.hpp"
#include "endohaptics/workflow/workflow_options.hpp"

namespace endohaptics::workflow {

//! What endohaptics-identify is asked to do. An empty optional takes the format's recommended
//! setting (workflow/format_defaults.hpp).
struct IdentifyRequest {
  std::vector<std::string> logs;              //!< log files, >= 1
  std::string format = "endowrist-2016";      //!< files::parse_log_format's names
  std::vector<std::string> inputs;            //!< input signal names; empty: the format's
  std::vector<std::string> outputs;           //!< output signal names; empty: the format's
  std::optional<std::string> order{};         //!< "N" or "auto"
  int max_order = 10;                         //!< largest order "auto" considers
  std::optional<std::string> method{};        //!< a comma list (parse_methods)
  std::optional<std::string> deadzone{};      //!< parse_deadzone's text
  std::optional<double> sample_time{};        //!< s (--ts)
  Preprocessing preprocessing{};              //!< for the fit; its cutoff: see `lowpass`
  std::optional<double> lowpass{};            //!< Hz, replaces preprocessing.cutoff
  std::string offset = "none";                //!< output offset mode name
  std::string input_offset = "none";          //!< input offset mode name
  std::string x0 = "steady";                  //!< steady or zero: the causal score's x0
  double warmup = ScoringOptions{}.warmup;    //!< s per segment left out of the score
  std::optional<double> max_time_constant{};  //!< s
  bool drop_non_finite = false;               //!< drop rows holding NaN/Inf
  //! "auto", "none" or a value in output units: the model's free-motion threshold
  //! (files::ModelFile::free_motion_threshold). auto: the 99th percentile of the chosen model's
  //! |estimate| over the training samples (after the warm-up) whose true output is exactly 0,
  //! what the model gives when nothing touches; refused with fewer than 100 such samples. Linear
  //! kinds only. Empty: none.
  std::optional<std::string> free_threshold{};
  //! Input 0's units, >= 0 (0: none): input 0 passes a play of this half width before the fit
  //! (files::ModelFile::current_play, written into the model); subspace families only: with
  //! joint models in the method list they meet the played subspace family on their own inputs,
  //! and one of them chosen is written with current_play 0.
  double current_play = 0.0;
  //! With current_play: the play's half width while the joint slides, in [0, current_play] (its
  //! Coulomb friction below the static; files::ModelFile::current_play_slide). None: a plain play.
  std::optional<double> current_play_slide{};
  //! With current_play: this times input 1 is the viscous friction's current, taken off while
  //! the joint slides (files::ModelFile::current_play_viscous). 0: none.
  double current_play_viscous = 0.0;
  //! The family choice searches a joint family's constants again inside each of its folds
  //! (WorkflowOptions::nested_joint_constants): its inner score then leaks nothing of the fold's
  //! held-out files, at about the folds' count times the search's cost.
  bool nested_joint_constants = false;
};

//! The request resolved, the logs prepared and the subspace family fitted: what run_identify
//! has made before it chooses the family (its hooks see this much).
struct IdentifyProgress {
  IdentifyRequest request;                     //!< as given
  LogSelection selection;                      //!< format, signals, CSV row time
  std::string method;                          //!< the --method text used
  WorkflowOptions options;                     //!< the subspace workflow's settings
  std::vector<files::ModelKind> joint_kinds;   //!< the joint-model families to fit
  bool subspace_family = false;                //!< a subspace or static method
  Preprocessing preprocessing;                 //!< for the subspace fit
  Preprocessing joint_preprocessing;           //!< the joint models' (no low-pass)
  double sample_time = 0.0;                    //!< s, the subspace grid
  double joint_sample_time = 0.0;              //!< s, the joint models' grid
  std::vector<PreparedLog> fit_logs;           //!< the logs the fit uses, subspace grid, per file
  std::vector<PreparedLog> score_logs;         //!< the logs scored, subspace grid, per file
  std::vector<PreparedLog> joint_logs;         //!< joint grid, prepared for scoring
  TimeConstantLimit time_constant_limit;       //!< what refuses a slow candidate
  std::vector<files::SignalInfo> input_info;   //!< inputs' names and units (first log)
  std::vector<files::SignalInfo> output_info;  //!< outputs' names and units (first log)
  std::optional<WorkflowResult> subspace;      //!< the subspace workflow, if fitted
  std::string subspace_left_out;               //!< why it was left out (joint models remain)

  //! The subspace workflow's result, or an empty one when it did not run.
  [[nodiscard]] const WorkflowResult& subspace_result() const;
};

//! Everything run_identify made: the progress, the family choice and the chosen model.
struct IdentifyReport : IdentifyProgress {
  ModelChoice choice;                  //!< the family chosen and its scores
  std::vector<FileComparison> oracle;  //!< per file, the oracle score (linear models only)
  double mean_rmse = 0.0;              //!< over the files, output units
  double mean_fit = 0.0;               //!< over the files, %
  files::ModelFile model;              //!< the chosen model, provenance notes set

  //! The chosen family is a joint force model (no linear state, no oracle score).
  [[nodiscard]] bool joint_chosen() const { return choice.model.is_joint_model(); }
};

//! Where run_identify reports progress while it runs (each may be empty): `text`, lines it
//! writes itself (a note, each log's summary) as they come; `prepared`, once the logs are on
//! their grids; `subspace_fitted`, once the subspace workflow ran, before the family choice.
struct IdentifyHooks {
  std::function<void(const std::string&)> text{};                  //!< lines, each ending in \n
  std::function<void(const IdentifyProgress&)> prepared{};         //!< logs prepared
  std::function<void(const IdentifyProgress&)> subspace_fitted{};  //!< before choose_family
  //! One line per model fitted and per fold scored while they run (WorkflowOptions::progress),
  //! so a long search shows it is moving.
  std::function<void(std::string_view)> progress{};
};

//! Runs endohaptics-identify's workflow: resolves the request against the format's defaults,
//! prepares every log (workflow/prepared_log.hpp), fits the subspace family
//! (identify_logs; left out with a reason when joint models remain and it cannot be fitted),
//! chooses the family (choose_family), scores the chosen model on each file and sets its
//! provenance notes. Throws Error on a bad request (naming the option), unreadable logs, or
//! when nothing can be fitted; scores are returned as computed (check_scores refuses
//! non-finite ones).
[[nodiscard]] ENDOHAPTICS_DECL IdentifyReport run_identify(const IdentifyRequest& request,
                                                           const IdentifyHooks& hooks = {});

//! The free-motion threshold identify's --free-threshold auto chooses from the training files'
//! causal comparisons: the 99th percentile of |estimate| over the scored samples (after each
//! segment's warm-up) whose true output is exactly 0. Throws Error with fewer than 100 such
//! samples.
[[nodiscard]] ENDOHAPTICS_DECL double free_motion_threshold_of(
    const std::vector<FileComparison>& files);

//! No false success: throws Error when a score of the chosen model is not finite.
ENDOHAPTICS_DECL void check_scores(const IdentifyReport& report);

}  // namespace endohaptics::workflow

#if !defined(ENDOHAPTICS_SEPARATE_COMPILATION)
#include "endohaptics/workflow/impl/identify_request.ipp"
#endif
