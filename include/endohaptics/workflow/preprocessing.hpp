//! @file
//! What is done to a log between reading and identification (worksheet 4.2.1): zero-phase
//! Butterworth low-pass (Hz), offset removal per signal, linear detrend, and the gap (s) and
//! segment length (samples) at which a log is split. Settings only: workflow/prepared_log.hpp
//! applies them; workflow/option_parsing.hpp reads and writes their text form.
#pragma once

#include <Eigen/Core>
#include <cstdint>
#include <string_view>

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

}  // namespace endohaptics::workflow
