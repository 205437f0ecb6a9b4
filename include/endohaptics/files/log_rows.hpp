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
using log_text::Number;
using log_text::parse_number;
using log_text::readable;
using log_text::split;
using log_text::Text;

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

inline void record(LogReport& report, const LogReadOptions& options, std::size_t line,
                   LogIssueKind kind, std::string detail) {
  if (report.issues.size() < options.max_issues) {
    report.issues.push_back({line, kind, std::move(detail)});
  }
}

inline std::string where(const Layout& layout, const std::string& path, std::size_t line) {
  return std::string(layout.function) + ": " + path + ":" + std::to_string(line) + ": ";
}

//! Parses the data lines from index `first` on; fills the report's per-row counts.
inline Rows parse_rows(const Text& text, std::size_t first, const Layout& layout,
                       const LogReadOptions& options, LogReport& report) {
  const std::size_t columns = layout.labels.size();
  Rows rows;
  rows.values.reserve(text.lines.size() * columns);
  std::vector<double> row(columns);
  std::size_t ordinal = 0;
  for (std::size_t li = first; li < text.lines.size(); ++li, ++ordinal) {
    const auto& line = text.lines[li];
    const auto fields = split(text.text(line), layout.separator);
    // Classify: the first bad field (in field order) is the reason a row is dropped; a row whose
    // fields all read but are too few is a short line.
    LogIssueKind kind = LogIssueKind::extra_fields;
    std::string detail;
    bool bad = false;
    for (std::size_t c = 0; !bad && c < std::min(columns, fields.size()); ++c) {
      const Number status = parse_number(fields[c], row[c]);
      if (status == Number::ok) continue;
      bad = true;
      kind = status == Number::empty        ? LogIssueKind::empty_field
             : status == Number::non_finite ? LogIssueKind::non_finite
                                            : LogIssueKind::non_numeric;
      detail = "field " + std::to_string(c + 1) + " (" + layout.labels[c] + "): '" +
               std::string(fields[c]) + "'";
    }
    if (!bad && fields.size() < columns) {
      bad = true;
      kind = LogIssueKind::short_line;
      detail = std::to_string(fields.size()) + " of " + std::to_string(columns) + " fields";
    }
    if (bad) {
      if (options.on_bad_line == OnBadRow::throw_error) {
        ENDOHAPTICS_THROW(Error(where(layout, report.source, line.number) +
                                std::string(to_string(kind)) + ": " + detail));
      }
      switch (kind) {
        case LogIssueKind::short_line:
          ++report.short_lines;
          break;
        case LogIssueKind::empty_field:
          ++report.empty_fields;
          break;
        case LogIssueKind::non_finite:
          ++report.non_finite;
          break;
        default:
          ++report.non_numeric;
          break;
      }
      record(report, options, line.number, kind, std::move(detail));
      continue;
    }
    const double t = layout.time_column >= 0 ? row[static_cast<std::size_t>(layout.time_column)]
                                             : static_cast<double>(ordinal) * layout.sample_time;
    if (!rows.time.empty() && !(t > rows.time.back())) {
      const bool repeated = t == rows.time.back();
      const LogIssueKind time_kind =
          repeated ? LogIssueKind::repeated_time : LogIssueKind::backward_time;
      std::string time_detail = "time " + readable(t) + " after " + readable(rows.time.back()) +
                                " (line " + std::to_string(rows.line.back()) + ")";
      if (options.on_bad_time == OnBadRow::throw_error) {
        ENDOHAPTICS_THROW(Error(where(layout, report.source, line.number) +
                                std::string(to_string(time_kind)) + ": " + time_detail));
      }
      ++(repeated ? report.repeated_time : report.backward_time);
      record(report, options, line.number, time_kind, std::move(time_detail));
      continue;
    }
    if (fields.size() > columns) {
      if (!options.allow_extra_fields) {
        ENDOHAPTICS_THROW(Error(where(layout, report.source, line.number) +
                                "extra fields: " + std::to_string(fields.size()) +
                                " fields, expected " + std::to_string(columns)));
      }
      ++report.extra_fields;
      record(report, options, line.number, LogIssueKind::extra_fields,
             std::to_string(fields.size()) + " fields, " + std::to_string(columns) + " used");
    }
    rows.values.insert(rows.values.end(), row.begin(), row.end());
    rows.time.push_back(t);
    rows.line.push_back(line.number);
  }
  return rows;
}

//! Shared by the readers: checks options, parses, then fills the time part of the report,
//! rebases time, and throws when fewer than min_rows rows are left.
inline Rows read_rows(const Text& text, std::size_t first, const Layout& layout,
                      const LogReadOptions& options, LogReport& report) {
  if (!std::isfinite(options.gap_threshold) || options.gap_threshold < 0) {
    ENDOHAPTICS_THROW(Error(std::string(layout.function) +
                            ": gap_threshold must be finite and >= 0, got " +
                            format(options.gap_threshold)));
  }
  Rows rows = parse_rows(text, first, layout, options, report);
  report.rows = rows.time.size();
  if (report.rows < std::max<std::size_t>(options.min_rows, 1)) {
    ENDOHAPTICS_THROW(Error(std::string(layout.function) + ": " + report.source +
                            ": no usable rows (" + std::to_string(report.rows) + " kept, " +
                            std::to_string(options.min_rows) + " needed)\n" + report.to_string()));
  }
  const Eigen::Map<const Eigen::VectorXd> time(rows.time.data(),
                                               static_cast<Eigen::Index>(rows.time.size()));
  report.median_step = identification::median_step(time);
  report.gap_threshold = options.gap_threshold > 0           ? options.gap_threshold
                         : std::isfinite(report.median_step) ? 5.0 * report.median_step
                                                             : 0.0;
  for (std::size_t k = 1; k < rows.time.size(); ++k) {
    const double step = rows.time[k] - rows.time[k - 1];
    report.largest_step = std::max(report.largest_step, step);
    if (report.gap_threshold > 0 && step > report.gap_threshold) {
      ++report.gaps;
      record(report, options, rows.line[k], LogIssueKind::gap,
             readable(step) + " s after line " + std::to_string(rows.line[k - 1]));
    }
  }
  std::stable_sort(report.issues.begin(), report.issues.end(),
                   [](const LogIssue& a, const LogIssue& b) { return a.line < b.line; });
  if (options.rebase_time) {
    report.time_offset = rows.time.front();
    for (double& t : rows.time) t -= report.time_offset;
  }
  return rows;
}

inline LogReport start_report(const Text& text, const std::string& path) {
  LogReport report;
  report.source = path;
  report.lines = text.total_lines;
  report.crlf_lines = text.crlf_lines;
  report.blank_lines = text.blank_lines;
  report.byte_order_mark = text.byte_order_mark;
  return report;
}

//! Column `c` of the row-major values as a vector.
inline Eigen::VectorXd column_of(const Rows& rows, std::size_t columns, std::size_t c) {
  const auto n = static_cast<Eigen::Index>(rows.time.size());
  Eigen::VectorXd v(n);
  for (Eigen::Index r = 0; r < n; ++r)
    v[r] = rows.values[static_cast<std::size_t>(r) * columns + c];
  return v;
}

}  // namespace detail::log_rows

}  // namespace endohaptics::files
