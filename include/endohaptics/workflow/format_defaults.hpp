//! @file
//! Recommended identify settings per log format: the signals a controller has and the
//! truth, the grid (s), the preprocessing for the fit (Hz), the methods, order and dead zones,
//! chosen by the causal score leave-one-session-out (UMN) and leave-one-file-out (2016
//! clamp-hits); see docs/identification_results.md. Flags given on the command line win.
#pragma once

#include <limits>
#include <string>
#include <vector>
#include "endohaptics/core/separate_compilation.hpp"

#include "endohaptics/files/log_reader.hpp"
#include "endohaptics/workflow/preprocessing.hpp"

namespace endohaptics::workflow {

//! What `endohaptics-identify --format F` does when no other flag says otherwise.
struct FormatDefaults {
  std::vector<std::string> inputs;   //!< signal names (empty: must be given)
  std::vector<std::string> outputs;  //!< signal names (empty: must be given)
  double sample_time = 0.0;          //!< s; 0: the median step of the first log
  Preprocessing preprocessing{};     //!< for the fit (scoring stays causal whatever it says)
  //! Comma list of n4sid, moesp, cva, best, static, stall_hold, push_load_observer,
  //! bidirectional_load_observer: every family is fitted and the best by the causal score on the
  //! training files is chosen.
  std::string method = "moesp";
  std::string order = "auto";  //!< N or auto
  //! Dead zone on inputs named "current" (the motor current: 4.2.3's friction); none elsewhere.
  std::string current_deadzone = "none";
  //! s, the grid of the joint models (stall_hold and the observers); 0: sample_time.
  double joint_sample_time = 0.0;
  //! s, WorkflowOptions::max_time_constant: 2 for the force-model formats (twice the longest
  //! warm-up: a force estimator starts from an unknown state); none (infinity) for generic
  //! records, where only the record itself bounds it (time_constant_limit).
  double max_time_constant = std::numeric_limits<double>::infinity();
};

//! The recommended settings of `format`.
[[nodiscard]] ENDOHAPTICS_DECL FormatDefaults format_defaults(files::LogFormat format);

//! The --deadzone text for `inputs` under `d`: current_deadzone on "current", none elsewhere.
[[nodiscard]] ENDOHAPTICS_DECL std::string default_deadzone(const FormatDefaults& d,
                                                            const std::vector<std::string>& inputs);

}  // namespace endohaptics::workflow

#if !defined(ENDOHAPTICS_SEPARATE_COMPILATION)
#include "endohaptics/workflow/impl/format_defaults.ipp"
#endif
