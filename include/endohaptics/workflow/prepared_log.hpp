//! @file
//! One log on the uniform grid k Ts (worksheet 4.2.1): the named inputs and outputs of a log
//! file (files/log_reader.hpp), resampled to Ts (s) and split at gaps, with what the reader and
//! the grid dropped. For fitting (`Preparation::fit`): linear interpolation, zero-phase low-pass
//! and offsets as a Preprocessing says. For scoring (`Preparation::score`): inputs held
//! (zero-order hold) and low-passed causally, velocities by backward difference, outputs as
//! logged. Signals keep their log units. Configuration time: allocates, throws endohaptics::Error.
#pragma once

#include <Eigen/Core>
#include <algorithm>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <sstream>
#include <string>
#include <utility>
#include <vector>
#include "endohaptics/core/separate_compilation.hpp"

#include "endohaptics/files/csv_log.hpp"
#include "endohaptics/files/endowrist_2016_log.hpp"
#include "endohaptics/files/log.hpp"
#include "endohaptics/files/log_reader.hpp"
#include "endohaptics/files/log_report.hpp"
#include "endohaptics/files/log_rows.hpp"
#include "endohaptics/files/umn_mis_2018_log.hpp"
#include "endohaptics/identification/signal.hpp"
#include "endohaptics/identification/subspace.hpp"
#include "endohaptics/workflow/error_context.hpp"
#include "endohaptics/workflow/preprocessing.hpp"

namespace endohaptics::workflow {

using namespace endohaptics::identification;  // the workflow composes the identification area

//! What a prepared log is for.
enum class Preparation : std::uint8_t {
  //! Identification data: linear interpolation, zero-phase (filtfilt) low-pass, offsets and
  //! detrend as the Preprocessing says. May look ahead and at the output: fitting is offline.
  fit,
  //! Scoring a force estimator: what a controller could compute in real time. Inputs
  //! on the grid by zero-order hold (the last logged sample at or before each grid time), the
  //! low-pass applied forward only (Butterworth `sosfilt` started at the steady state of the first
  //! sample), endowrist-2016 `velocity` by backward difference of `position`; no input offsets;
  //! outputs as logged (linear interpolation onto the grid, no filter, offset or detrend).
  score,
};

//! Which file format and which named signals to read.
struct LogSelection {
  files::LogFormat format = files::LogFormat::endowrist_2016;  //!< reader
  std::vector<std::string> inputs;                             //!< signal names, >= 1
  std::vector<std::string> outputs;                            //!< signal names, >= 1
  double csv_row_time = 1.0;     //!< s per row of a CSV without a "time" column
  bool drop_non_finite = false;  //!< false: a NaN/Inf field fails; true: its row is dropped
};

//! One log on the grid k Ts: gap-free segments of inputs and outputs, and what was done.
struct PreparedLog {
  std::string source;              //!< file
  files::LogReport report;         //!< what the reader dropped or repaired
  std::vector<DataSet> segments;   //!< u: N x nu, y: N x ny per gap-free stretch
  std::vector<double> start_time;  //!< s, time of row 0 of each segment (rebased log time)
  double sample_time = 0.0;        //!< s
  Preparation preparation = Preparation::fit;  //!< what it was prepared for
  std::size_t gaps = 0;                        //!< time steps > max_gap that split the log
  std::size_t dropped_segments = 0;            //!< stretches shorter than min_segment
  Eigen::VectorXd input_offsets;               //!< removed from each input, input units
  Eigen::VectorXd output_offsets;              //!< removed from each output, output units

  //! Grid samples over all segments.
  [[nodiscard]] Eigen::Index samples() const noexcept {
    Eigen::Index n = 0;
    for (const auto& s : segments) n += s.u.rows();
    return n;
  }
};

//! Reads `path` as `sel` says (no checks beyond the reader's).
[[nodiscard]] ENDOHAPTICS_DECL files::Log read_selected_format(const std::string& path,
                                                               const LogSelection& sel);

//! Signals of `format` that a robot controller has, for formats that log more than that (the
//! UMN rig's jaw-side sensors); empty: no restriction. `motor_position` is left out although the
//! controller has its increments: its zero differs between sessions (use motor_velocity).
[[nodiscard]] ENDOHAPTICS_DECL std::vector<std::string> controller_signals(files::LogFormat format);

namespace detail {

//! (x[k] - x[k-1]) / (t[k] - t[k-1]), 0 at the first sample and after a step > max_gap: what a
//! controller computes from its encoder each period.
ENDOHAPTICS_DECL Eigen::VectorXd backward_difference(const Eigen::VectorXd& time,
                                                     const Eigen::VectorXd& x, double max_gap);

}  // namespace detail

//! The default resampling period: the median time step of the log at `path` (s), rounded to six
//! significant digits; for a CSV without time column sel.csv_row_time. Throws Error as the reader.
[[nodiscard]] ENDOHAPTICS_DECL double default_sample_time(const std::string& path,
                                                          const LogSelection& sel);

namespace detail {

//! Preparation::score of `prepare_log` on the selected `signals` (inputs first, nu of them).
ENDOHAPTICS_DECL PreparedLog prepare_for_scoring(const std::string& path, const files::Log& log,
                                                 Eigen::MatrixXd signals, Eigen::Index nu,
                                                 const LogSelection& sel, double ts,
                                                 const Preprocessing& pre,
                                                 Eigen::Index min_samples);

}  // namespace detail

//! Reads `path`, selects the named signals, resamples to `ts` (split at gaps), filters and
//! removes offsets as `pre` and `use` say. Throws Error naming the file: unreadable, unknown
//! signal (listing the known ones), an input a controller does not have (controller_signals), a
//! signal named twice, non-finite values (unless drop_non_finite), fewer than `min_samples` or
//! more than limits::max_grid_samples grid samples, bad options (`validate`).
[[nodiscard]] ENDOHAPTICS_DECL PreparedLog prepare_log(const std::string& path,
                                                       const LogSelection& sel, double ts,
                                                       const Preprocessing& pre,
                                                       Eigen::Index min_samples = 20,
                                                       Preparation use = Preparation::fit);

//! One-paragraph summary: reader report counts, grid, segments, offsets.
[[nodiscard]] ENDOHAPTICS_DECL std::string summary(const PreparedLog& log);

}  // namespace endohaptics::workflow

#if !defined(ENDOHAPTICS_SEPARATE_COMPILATION)
#include "endohaptics/workflow/impl/prepared_log.ipp"
#endif
