//! @file
//! A model file replayed on prepared logs and scored as a force estimator (worksheet 4.2):
//! input maps, linear block and output maps simulated segment by segment from an
//! initial state set from the inputs alone (steady state of the first input sample; or zero, or
//! the file's x0), the first `warmup` s of each segment left out of the score, then NRMSE fit (%),
//! correlation, RMSE (output units) and the delay of the estimate (s, cross-correlation peak) over
//! the whole file (identification/fit_metrics.hpp). `oracle` (x0 by least squares on the measured
//! output, MATLAB compare's default) is there only as a labelled comparison.
//! Configuration time: throws endohaptics::Error.
#pragma once

#include <Eigen/Core>
#include <Eigen/LU>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <limits>
#include <optional>
#include <string>
#include <string_view>
#include <vector>
#include "endohaptics/core/separate_compilation.hpp"

#include "endohaptics/files/model_file.hpp"
#include "endohaptics/identification/fit_metrics.hpp"
#include "endohaptics/identification/hammerstein_wiener_fit.hpp"
#include "endohaptics/identification/subspace.hpp"
#include "endohaptics/model/state_space.hpp"
#include "endohaptics/model/static_map.hpp"
#include "endohaptics/model/static_nonlinearity.hpp"
#include "endohaptics/workflow/error_context.hpp"
#include "endohaptics/workflow/joint_models.hpp"
#include "endohaptics/workflow/prepared_log.hpp"
#include "endohaptics/workflow/preset_models.hpp"

namespace endohaptics::workflow {

using namespace endohaptics::identification;  // the workflow composes the identification area

//! How replay/compare set the initial state of every segment.
enum class InitialStateMode : std::uint8_t {
  steady,  //!< steady state for the first (mapped) input sample: inputs only (the default)
  zero,    //!< x0 = 0
  stored,  //!< the model file's x0 (a model parameter, e.g. the static baseline's constant)
  oracle,  //!< least squares on the measured output (MATLAB compare's default): NOT causal
};

//! Lower-case name ("steady", "zero", "stored", "oracle").
[[nodiscard]] constexpr std::string_view to_string(InitialStateMode mode) noexcept {
  switch (mode) {
    case InitialStateMode::steady:
      return "steady";
    case InitialStateMode::zero:
      return "zero";
    case InitialStateMode::stored:
      return "stored";
    case InitialStateMode::oracle:
      return "oracle";
  }
  return "unknown";
}

//! True when the mode uses nothing but the inputs (and the model) to set the state.
[[nodiscard]] constexpr bool is_causal(InitialStateMode mode) noexcept {
  return mode != InitialStateMode::oracle;
}

//! How a model is scored on a log.
struct ScoringOptions {
  InitialStateMode initial_state = InitialStateMode::steady;  //!< how x0 is set per segment
  //! s at the start of each segment simulated but left out of the score (the state settles
  //! from its input-only start); at most max_warmup. 0 with `oracle` (MATLAB compare).
  double warmup = 0.5;
  double max_lag = 1.0;  //!< s, largest |delay| searched by the cross-correlation
  //! Set: the model is this clamp preset and runs as the bridge runs it (simulate_clamp_preset,
  //! from its reset state; oracle refused); the model file then gives only names, units and Ts.
  std::optional<estimation::ClampPreset> clamp_preset{};
};

//! Largest warm-up accepted, s (a stated warm-up of at most 1 s).
inline constexpr double max_warmup = 1.0;

//! A model simulated on one prepared log, segment by segment, and its scores over the whole file.
struct FileComparison {
  std::string source;                  //!< file
  std::vector<Eigen::MatrixXd> y;      //!< measured output per segment (as prepared)
  std::vector<Eigen::MatrixXd> y_hat;  //!< simulated output per segment
  std::vector<double> start_time;      //!< s, per segment
  double sample_time = 0.0;            //!< s
  Eigen::Index warmup_samples = 0;     //!< per segment, left out of the scores
  Eigen::Index scored_samples = 0;     //!< over all segments
  Eigen::VectorXd fit;                 //!< NRMSE fit per output over the scored samples, %
  Eigen::VectorXd correlation;         //!< per output
  Eigen::VectorXd rmse;                //!< per output, output units
  Eigen::VectorXd delay;               //!< per output, s: lag of the estimate behind the truth

  //! Mean of `fit` over the outputs, %.
  [[nodiscard]] double mean_fit() const { return fit.mean(); }
  //! Mean of `rmse` over the outputs, output units.
  [[nodiscard]] double mean_rmse() const { return rmse.mean(); }
};

//! The state x with x = A x + B u0 (the steady state for a constant input u0, already through
//! the input maps). A model whose A has no such state (an eigenvalue at 1): when it is the
//! static baseline's constant (A = I, B = 0) its stored x0; otherwise throws Error.
[[nodiscard]] ENDOHAPTICS_DECL Eigen::VectorXd steady_initial_state(
    const model::DynamicStateSpace<>& linear, const Eigen::VectorXd& u0);

//! Simulates the model file (input maps, linear block, output maps; or a joint model, kinds
//! stall_hold and the observers, or the clamp preset `options.clamp_preset`, from its start
//! state whatever `options.initial_state` says but oracle, which it refuses) on every segment of
//! `log` from x0 as `options.initial_state` says, leaves the first `options.warmup` s of each
//! segment (all but its last sample when shorter) out, and scores the rest of the file together.
//! Throws Error when the log's input or output count differs from the model's, or the warm-up is
//! outside [0, max_warmup].
[[nodiscard]] ENDOHAPTICS_DECL FileComparison compare_log(const files::ModelFile& model,
                                                          const PreparedLog& log,
                                                          const ScoringOptions& options = {});

//! Throws Error naming the file and the output when a score of `c` is not finite, so that a
//! program never reports such a run as a success: a simulated output that diverges (an unstable
//! model: fit -Inf), a constant measured output the model does not match (fit -Inf), or a
//! constant measured or simulated output (correlation undefined). `outputs` names the outputs
//! (fewer names: numbered).
ENDOHAPTICS_DECL void require_finite_scores(const FileComparison& c,
                                            const std::vector<std::string>& outputs);

}  // namespace endohaptics::workflow

#if !defined(ENDOHAPTICS_SEPARATE_COMPILATION)
#include "endohaptics/workflow/impl/model_comparison.ipp"
#endif
