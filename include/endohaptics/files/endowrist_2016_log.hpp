//! @file
//! Reader of the 2016 EndoWrist logs (worksheet appendix E; ../shared/data/endowrist-2016/
//! README.md): measurement logs (time s, load-cell V, force kN -> N, setpoint/position rad,
//! currents A) and friction logs (time, encoder ticks, current A), with velocity (rad/s).
//! Configuration time: allocates, throws endohaptics::Error naming file, line and field.
#pragma once

#include <Eigen/Core>
#include <algorithm>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <limits>
#include <map>
#include <numbers>
#include <string>
#include <string_view>
#include <utility>
#include <vector>
#include "endohaptics/core/separate_compilation.hpp"

#include "endohaptics/core/error.hpp"
#include "endohaptics/files/log.hpp"
#include "endohaptics/files/log_report.hpp"
#include "endohaptics/files/log_rows.hpp"
#include "endohaptics/files/log_text.hpp"
#include "endohaptics/identification/signal.hpp"

namespace endohaptics::files {

//! Which kind of 2016 log a file is.
enum class Endowrist2016Layout : std::uint8_t {
  detect,       //!< from the most common field count of the first 20 data lines (>= 7 | 3-4)
  measurement,  //!< 7 columns: time, load-cell V, force kN, setpoint, position, current, demand
  friction,     //!< 3 columns: time, encoder ticks, current (a 4th column is ignored)
};

//! Settings of `read_endowrist_2016`.
struct Endowrist2016Options {
  LogReadOptions read;                                       //!< policies shared by the readers
  Endowrist2016Layout layout = Endowrist2016Layout::detect;  //!< measurement or friction log
  double force_scale = 1000.0;  //!< N per logged force unit (the logs hold kN)
  //! Encoder ticks -> rad after gearing (friction logs): 2 pi / 76000, the quantum of the
  //! measurement logs' position column (docs/models/friction_model.md).
  double radians_per_tick = 2.0 * std::numbers::pi / 76000.0;
  //! Consistency check of the load cell: force [N] = force_per_volt x voltage [V] in every 2016
  //! log but pitch-up-01 (least squares, residual < 1e-6 N); 0 disables the check.
  double force_per_volt = 2.5;
  double force_tolerance = 0.01;  //!< N, allowed |force - force_per_volt x voltage|
};

//! Reads a 2016 EndoWrist log. Measurement logs give the signals loadcell_voltage (V),
//! force (N), setpoint (rad), position (rad), current (A), current_demand (A) and velocity
//! (rad/s); friction logs give ticks, position (rad), current (A) and velocity (rad/s).
//! velocity = identification::differentiate(time, position, report.gap_threshold): the secant
//! over the neighbours on the logged stamps, one-sided next to gaps. A header line is skipped;
//! CR LF is accepted; time is rebased to 0 (report.time_offset). Throws Error (file, line,
//! field) when the file cannot be read, the layout is not recognised, a policy says throw, or
//! fewer than read.min_rows rows are usable.
[[nodiscard]] ENDOHAPTICS_DECL Log read_endowrist_2016(const std::string& path,
                                                       const Endowrist2016Options& options = {});

}  // namespace endohaptics::files

#if !defined(ENDOHAPTICS_SEPARATE_COMPILATION)
#include "endohaptics/files/impl/endowrist_2016_log.ipp"
#endif
