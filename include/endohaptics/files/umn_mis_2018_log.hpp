//! @file
//! Reader of the University of Minnesota da Vinci grasper characterisation logs (O'Neill,
//! Stephens, Kowalewski, RA-L 2018; ../shared/data/umn-mis-tool-2018/README.md): `%` header lines
//! (free text, `%key=value`, a last line naming the columns), then 10 comma-separated columns at
//! 1 kHz, converted to SI with the README's constants. Configuration time: allocates, throws
//! endohaptics::Error naming file, line and field.
#pragma once

#include <Eigen/Core>
#include <cmath>
#include <cstddef>
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

namespace endohaptics::files {

//! The README's conversion constants (defaults) of `read_umn_mis_2018`.
struct UmnMis2018Options {
  LogReadOptions read;                        //!< policies shared by the readers
  double futek_newton_metres = 0.000039811;   //!< N m per Futek count (columns 3 and 6)
  double motor_counts_per_rev = 4196.0 * 35;  //!< column 9, per turn of the gearbox output
  double spindle_counts_per_rev = 8192.0;     //!< column 2 (CUI encoder on the input spindle)
  double jaw_counts_per_rev = 4000.0;         //!< column 5 (Maxon encoder, jaw side)
};

namespace detail::umn_mis_2018 {

//! Splits "%key=value" into (key, value); false for any other header line.
ENDOHAPTICS_DECL bool key_value(std::string_view line, std::pair<std::string, std::string>& out);

}  // namespace detail::umn_mis_2018

//! Reads one UMN run. Signals (what a robot controller has first, then the instrumentation):
//! - `current` (A, column 4, the Maxon controller's measured motor current);
//! - `current_command` (1, column 8, the driving motor's command, -1..1);
//! - `motor_position` (rad of the gearbox output = the tool's input spindle, column 9);
//! - `motor_velocity` (rad/s): the backward difference of motor_position over the logged stamps,
//!   (p[k] - p[k-1]) / (t[k] - t[k-1]), 0 at the first row: causal, what a controller computes
//!   from its encoder each period (quantum 2 pi / 146860 rad per ms = 0.043 rad/s);
//! - `grip_torque` (mN m, column 6 x futek_newton_metres x 1000): the truth at the jaws, as the
//!   sensor reads it (no zero correction: see docs/identification.md);
//! - `spindle_position` (rad, column 2), `spindle_torque` (mN m, column 3), `jaw_position` (rad,
//!   column 5), `reaction_command` (A, column 7), `trajectory_target` (rad, column 10 in motor
//!   counts): instrumentation a robot does not have.
//! `%key=value` header lines go to Log::metadata in file order. Time (column 1) is written in ms
//! but steps by 0.001, so it is read as seconds (README), then rebased to 0.
[[nodiscard]] ENDOHAPTICS_DECL Log read_umn_mis_2018(const std::string& path,
                                                     const UmnMis2018Options& options = {});

}  // namespace endohaptics::files

#if !defined(ENDOHAPTICS_SEPARATE_COMPILATION)
#include "endohaptics/files/impl/umn_mis_2018_log.ipp"
#endif
