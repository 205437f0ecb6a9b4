//! @file
//! Reader of generic CSV logs whose first line names the columns (e.g. ../shared/data/daisy/
//! *.csv): separator ',', ';', tab or blanks, time from a named column (s) or the row ordinal.
//! Configuration time: allocates, throws endohaptics::Error naming file, line and field.
#pragma once

#include <Eigen/Core>
#include <algorithm>
#include <cstddef>
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

//! Settings of `read_csv`.
struct CsvOptions {
  LogReadOptions read;  //!< policies shared by the readers
  //! ',', ';', `\t` (tab) or ' ' (runs of blanks/tabs); '\0': ';' if the header has one, else
  //! ',' if it has one, else blanks.
  char separator = '\0';
  //! Column holding time in s; empty: the column named "time" if any, else time = row ordinal
  //! x sample_time (the ordinal counts dropped rows too, so a drop leaves a hole).
  std::string time_column;
  double sample_time = 1.0;  //!< s per row when there is no time column
  //! Non-empty: names of the columns of a file without header line (a header is still skipped).
  std::vector<std::string> column_names;
};

//! Reads a CSV whose first line names the columns (e.g. ../shared/data/daisy/*.csv). Names are
//! trimmed and unquoted. All columns but the time column become signals. Throws Error (file,
//! line, field) for an unreadable file, a missing/duplicate/empty column name, an unknown
//! time_column, a policy that says throw, or fewer than read.min_rows usable rows.
[[nodiscard]] ENDOHAPTICS_DECL Log read_csv(const std::string& path,
                                            const CsvOptions& options = {});

}  // namespace endohaptics::files

#if !defined(ENDOHAPTICS_SEPARATE_COMPILATION)
#include "endohaptics/files/impl/csv_log.ipp"
#endif
