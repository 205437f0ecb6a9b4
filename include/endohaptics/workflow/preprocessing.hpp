//! @file
//! What is done to a log between reading and identification (worksheet 4.2.1): zero-phase
//! Butterworth low-pass (Hz), offset removal per signal, linear detrend, and the gap (s) and
//! segment length (samples) at which a log is split, and the ranges they may take. Settings and
//! their check only: workflow/prepared_log.hpp applies them; workflow/option_parsing.hpp reads
//! and writes their text form.
#pragma once

#include <Eigen/Core>
#include <cmath>
#include <cstdint>
#include <string>
#include <string_view>
#include "endohaptics/core/separate_compilation.hpp"

#include "endohaptics/core/error.hpp"

namespace endohaptics::workflow {

//! How an offset is removed from a signal, one offset per file and signal.
enum class OffsetMode : std::uint8_t {
  none,    //!< kept as logged
  start,   //!< median of the first Preprocessing::offset_duration s (after filtering)
  median,  //!< median over the whole file (the load-cell zero when contact is the exception)
  mean,    //!< mean over the whole file
};

//! Lower-case name ("none", "start", "median", "mean").
[[nodiscard]] constexpr std::string_view to_string(OffsetMode mode) noexcept {
  switch (mode) {
    case OffsetMode::none:
      return "none";
    case OffsetMode::start:
      return "start";
    case OffsetMode::median:
      return "median";
    case OffsetMode::mean:
      return "mean";
  }
  return "unknown";
}

//! What is done to a log between reading and identification (worksheet 4.2.1).
struct Preprocessing {
  double cutoff = 0.0;                          //!< Hz, zero-phase Butterworth low-pass; 0: none
  int filter_order = 4;                         //!< Butterworth order, 1..32
  OffsetMode output_offset = OffsetMode::none;  //!< offset removed from every output
  OffsetMode input_offset = OffsetMode::none;   //!< offset removed from every input
  double offset_duration = 0.5;                 //!< s, window of OffsetMode::start
  bool detrend = false;           //!< least-squares line removed from the outputs of each segment
  double max_gap = 0.0;           //!< s, longer time steps split a log; 0: 5 x max(Ts, median step)
  Eigen::Index min_segment = 20;  //!< samples; shorter gap-free stretches are dropped
};

//! The ranges the workflow accepts (inclusive), stated once for `validate` and the programs'
//! options. The sizes bound memory and time: a log gives at most max_grid_samples samples.
namespace limits {
inline constexpr Eigen::Index max_grid_samples = 10'000'000;  //!< grid samples per log
inline constexpr double min_sample_time = 1e-9;               //!< s
inline constexpr double max_sample_time = 1e6;                //!< s
inline constexpr double max_cutoff = 1e9;                     //!< Hz (also < Nyquist)
inline constexpr int min_filter_order = 1;                    //!< Butterworth order
inline constexpr int max_filter_order = 32;                   //!< Butterworth order
inline constexpr double min_offset_duration = 1e-9;           //!< s
inline constexpr double max_duration = 1e9;                   //!< s, offset window and max gap
inline constexpr Eigen::Index min_segment = 2;                //!< samples
inline constexpr int max_order = 100;                         //!< model order
}  // namespace limits

//! Throws Error naming the setting, its value and its range when `p` holds a value outside
//! the ranges of `limits` (or a non-finite one).
ENDOHAPTICS_DECL void validate(const Preprocessing& p);

}  // namespace endohaptics::workflow

#if !defined(ENDOHAPTICS_SEPARATE_COMPILATION)
#include "endohaptics/workflow/impl/preprocessing.ipp"
#endif
