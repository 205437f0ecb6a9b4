//! @file
//! The rows of a delimited log, shared by the readers: the policies they apply (OnBadRow,
//! LogReadOptions) and the row parser that applies them (namespace detail::log_rows): classifies
//! every dropped row and every repaired one in a LogReport, finds time gaps (s) and rebases time.
//! Configuration time: allocates, throws endohaptics::Error naming file, line and field.
#pragma once

#include <Eigen/Core>
#include <algorithm>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <string>
#include <string_view>
#include <utility>
#include <vector>
#include "endohaptics/core/separate_compilation.hpp"

#include "endohaptics/core/error.hpp"
#include "endohaptics/files/log_report.hpp"
#include "endohaptics/files/log_text.hpp"
#include "endohaptics/identification/signal.hpp"

namespace endohaptics::files {

//! What to do with a row that cannot be used.
enum class OnBadRow : std::uint8_t {
  drop,         //!< skip it, count it in the report
  throw_error,  //!< throw endohaptics::Error naming file, line and field
};

//! Settings shared by the readers.
struct LogReadOptions {
  OnBadRow on_bad_line = OnBadRow::drop;  //!< empty/short/non-numeric/non-finite rows
  OnBadRow on_bad_time = OnBadRow::drop;  //!< repeated or backward time stamps
  bool allow_extra_fields = true;         //!< false: a row with extra fields throws
  bool rebase_time = true;                //!< subtract the first kept time stamp
  double gap_threshold = 0;               //!< s; 0: 5 x the median time step
  std::size_t min_rows = 2;               //!< fewer usable rows throw (0 acts as 1)
  std::size_t max_issues = 20;            //!< defects recorded with their line in the report
  //! Largest file read, bytes: a larger one (or one that grows beyond it while being read) is
  //! refused, naming the file, its size and this option (files/log_text.hpp).
  std::uint64_t max_bytes = default_log_max_bytes;

  //! Every defect throws (extra fields too); gaps are still only reported.
  [[nodiscard]] static LogReadOptions strict() {
    LogReadOptions o;
    o.on_bad_line = OnBadRow::throw_error;
    o.on_bad_time = OnBadRow::throw_error;
    o.allow_extra_fields = false;
    return o;
  }
};

namespace detail::log_rows {

using identification::detail::signal::format;
using log_text::Lines;
using log_text::Number;
using log_text::parse_number;
using log_text::readable;
using log_text::split;

//! How the data rows of a file are laid out.
struct Layout {
  std::string_view function;        //!< for messages
  std::vector<std::string> labels;  //!< column labels, for messages; size = columns
  char separator = ',';
  std::ptrdiff_t time_column = 0;  //!< < 0: time = data-line ordinal x sample_time
  double sample_time = 1.0;
};

//! Rows kept, row-major, and their time stamps (not yet rebased).
struct Rows {
  std::vector<double> values;
  std::vector<double> time;
  std::vector<std::size_t> line;
};

ENDOHAPTICS_DECL void record(LogReport& report, const LogReadOptions& options, std::size_t line,
                             LogIssueKind kind, std::string detail);

ENDOHAPTICS_DECL std::string where(const Layout& layout, const std::string& path, std::size_t line);

//! Parses the data lines not yet taken from `lines`, to the end of the file; fills the report's
//! per-row counts.
ENDOHAPTICS_DECL Rows parse_rows(Lines& lines, const Layout& layout, const LogReadOptions& options,
                                 LogReport& report);

//! Shared by the readers: checks options, parses the rest of `lines`, then fills the line counts
//! and the time part of the report, rebases time, and throws when fewer than min_rows rows are
//! left.
ENDOHAPTICS_DECL Rows read_rows(Lines& lines, const Layout& layout, const LogReadOptions& options,
                                LogReport& report);

//! The report of file `path` before its rows are read (read_rows adds the line counts).
ENDOHAPTICS_DECL LogReport start_report(const std::string& path);

//! Column `c` of the row-major values as a vector.
ENDOHAPTICS_DECL Eigen::VectorXd column_of(const Rows& rows, std::size_t columns, std::size_t c);

}  // namespace detail::log_rows

}  // namespace endohaptics::files

#if !defined(ENDOHAPTICS_SEPARATE_COMPILATION)
#include "endohaptics/files/impl/log_rows.ipp"
#endif
