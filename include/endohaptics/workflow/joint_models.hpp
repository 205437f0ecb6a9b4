//! @file
//! The joint force models in the identify/replay workflow: estimation::StallHold
//! (model-file kind "stall_hold", docs/research_force_models.md A1), PushLoadObserver
//! ("push_load_observer", K2) and BidirectionalLoadObserver ("bidirectional_load_observer", K7),
//! simulated causally on prepared logs (inputs: current A, velocity rad/s; the observers' encoder
//! angle is the running sum of the velocity times the sample time, of which they use only the
//! increments), fitted from logs prepared for scoring (workflow/stall_hold_fit.hpp,
//! push_load_observer_fit.hpp, bidirectional_observer_fit.hpp), and compared with the subspace
//! candidates by an inner cross-validation over the training files.
//! Configuration time: allocates, throws endohaptics::Error.
#pragma once

#include <Eigen/Core>
#include <cmath>
#include <cstddef>
#include <limits>
#include <optional>
#include <string>
#include <string_view>
#include <vector>
#include "endohaptics/core/separate_compilation.hpp"

#include "endohaptics/core/error.hpp"
#include "endohaptics/estimation/bidirectional_load_observer.hpp"
#include "endohaptics/estimation/push_load_observer.hpp"
#include "endohaptics/estimation/simulate.hpp"
#include "endohaptics/estimation/stall_hold.hpp"
#include "endohaptics/files/model_file.hpp"
#include "endohaptics/model/fit_metric.hpp"
#include "endohaptics/workflow/bidirectional_observer_fit.hpp"
#include "endohaptics/workflow/error_context.hpp"
#include "endohaptics/workflow/method.hpp"
#include "endohaptics/workflow/prepared_log.hpp"
#include "endohaptics/workflow/push_load_observer_fit.hpp"
#include "endohaptics/workflow/stall_hold_fit.hpp"

namespace endohaptics::workflow {

//! The joint-model kind named by a --method value ("stall_hold", "push_load_observer",
//! "bidirectional_load_observer": method_names), or none.
[[nodiscard]] ENDOHAPTICS_DECL std::optional<files::ModelKind> joint_model_kind(
    std::string_view method);

//! A joint-model file (kind stall_hold or an observer) run causally on one segment from
//! its start state: `u` is N x 2 (current A, velocity rad/s), or N x 3 with the current command
//! for an observer that refers its current to it; one output value per row. Throws Error on
//! another kind, another input count, or a non-finite signal or result (naming the row).
[[nodiscard]] ENDOHAPTICS_DECL Eigen::VectorXd simulate_joint_model(const files::ModelFile& model,
                                                                    const Eigen::MatrixXd& u);

//! The constants of a joint-model fit that no physics fixes, as chosen by cross-validation on one
//! set of training files (choose_joint_constants). fit_joint_model takes them to refit the least-
//! squares parts on a subset of those files without searching again: choose_family's inner folds
//! do so, as they refit the subspace family with its structure chosen on all training files.
struct JointConstants {
  files::ModelKind kind = files::ModelKind::stall_hold;  //!< the joint-model kind they are for
  std::size_t files = 0;  //!< how many training files they were chosen on
  //! Kind stall_hold: the velocity threshold and the two time constants, and how they were chosen.
  std::optional<StallHoldSelection> stall_hold{};
  //! Kind bidirectional_load_observer: the noise rule and the front end, and how they were chosen.
  std::optional<BidirectionalSelection> bidirectional{};
  //! Kind bidirectional_load_observer: the encoder's step, rad, when the angle is quantised (the
  //! velocity threshold is then one step per sample, not searched).
  std::optional<double> encoder_step{};
};

//! A joint model fitted on logs, with its causal training score.
struct JointModelFit {
  files::ModelFile model;              //!< a joint-model kind
  std::vector<double> training_fit{};  //!< causal fit % per experiment (segment) after the warm-up
  std::string summary{};               //!< one line: the fitted values, for identify's report
  JointConstants constants{};          //!< the constants the fit used (given or chosen)
  //! Constant searches this fit ran: 1 when it chose the constants itself (stall_hold and
  //! bidirectional_load_observer without given constants), else 0 (given, or none to choose:
  //! push_load_observer). Counted by choose_family (ModelChoice::constant_searches).
  std::size_t constant_searches = 0;
};

//! The constants fit_joint_model would choose for `kind` on `logs` (same arguments and checks as
//! fit_joint_model; see there), without the final fit: the blocked cross-validation over the
//! logs (choose_stall_hold_settings, choose_bidirectional_settings; with one log the priors). For
//! push_load_observer there is nothing to choose (its priors come from the training output) and
//! only the kind and the file count are set. Throws Error on another kind or unusable data.
[[nodiscard]] ENDOHAPTICS_DECL JointConstants
choose_joint_constants(files::ModelKind kind, const std::vector<PreparedLog>& logs,
                       const std::vector<files::SignalInfo>& inputs,
                       const std::vector<files::SignalInfo>& outputs, double warmup);

//! Fits a joint model of `kind` on `logs` (prepared for scoring: what a controller has; inputs
//! current and velocity, one output; for the observer optionally a third input, the current
//! command, to which the current is then referred; every segment longer than the warm-up), at the
//! logs' sample time. StallHold: the dead zone table 5.2's (physical), the velocity threshold and
//! the two time constants by choose_stall_hold_settings over blocked_folds of the logs (with one
//! log the priors of StallHoldParameters), the gain and the loaded side by least squares
//! (fit_stall_hold).
//! PushLoadObserver: the priors of PushLoadObserverParameters, P0 = the variance of the training
//! output, Q = (0.03 max |output|)^2 Ts per step (a random walk of 3 % of the range per root
//! second; 1e-8 (N m)^2 per ms for the UMN grasper, the research note's), both push signs fitted
//! (fit_push_load_observer), the one in which the motor works against the load kept (the
//! current's magnitude grows with the load at the training-mean load), then the better causal
//! training RMSE. BidirectionalLoadObserver: the velocity threshold one encoder step per sample
//! when the angle is quantised (encoder_step), the noise rule and the other front-end constants
//! by choose_bidirectional_settings over blocked_folds of the logs (with one log the priors),
//! everything else by fit_bidirectional_load_observer (no sign to choose: forward and backward
//! enter alike). With `constants` (from choose_joint_constants, or a fit's `constants`, for the
//! same kind; e.g. chosen on a superset of `logs`) those are used and nothing is searched: only
//! the least-squares parts (and the observers' data-derived priors) are fitted on `logs`.
//! Throws Error on another kind, constants of another kind, or unusable data.
[[nodiscard]] ENDOHAPTICS_DECL JointModelFit fit_joint_model(
    files::ModelKind kind, const std::vector<PreparedLog>& logs,
    const std::vector<files::SignalInfo>& inputs, const std::vector<files::SignalInfo>& outputs,
    double warmup, const JointConstants* constants = nullptr);

//! One model family scored by the inner cross-validation of `choose_family`.
struct FamilyScore {
  std::string family{};             //!< e.g. "moesp + dead zone", "stall_hold"
  std::vector<double> fold_fit{};   //!< causal mean fit % on each fold's held-out files
  std::vector<double> fold_rmse{};  //!< causal mean RMSE on each fold's held-out files
  double mean_fit = -std::numeric_limits<double>::infinity();  //!< over the folds, %
  double mean_rmse = std::numeric_limits<double>::infinity();  //!< over the folds, output units
  std::string failure{};  //!< why a fold could not be fitted (the family then loses)
};

//! The folds of the inner cross-validation over `files` training files: min(files, 5) folds,
//! file i held out in fold i mod folds (leave-one-file-out up to 5 files). Empty for < 2 files.
[[nodiscard]] ENDOHAPTICS_DECL std::vector<std::vector<std::size_t>> inner_folds(std::size_t files);

//! Contiguous folds over `files` training files in the order given: min(files, 5) blocks of
//! consecutive files (sizes differing by at most one, the larger first). Files given in recording
//! order then hold out a stretch of the recording, so that a choice must carry over the drift
//! between stretches (the kind of change another session brings), not only to a neighbouring run.
//! Empty for < 2 files.
[[nodiscard]] ENDOHAPTICS_DECL std::vector<std::vector<std::size_t>> blocked_folds(
    std::size_t files);

}  // namespace endohaptics::workflow

#if !defined(ENDOHAPTICS_SEPARATE_COMPILATION)
#include "endohaptics/workflow/impl/joint_models.ipp"
#endif
