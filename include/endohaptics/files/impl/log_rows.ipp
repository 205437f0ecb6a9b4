//! @file
//! Function bodies of files/log_rows.hpp: included at its end (header-only, the default), or
//! compiled once with ENDOHAPTICS_SEPARATE_COMPILATION (core/separate_compilation.hpp).
#pragma once

#include "endohaptics/files/log_rows.hpp"

namespace endohaptics::files {
namespace detail::log_rows {

ENDOHAPTICS_DECL void record(LogReport& report, const LogReadOptions& options, std::size_t line,
                             LogIssueKind kind, std::string detail) {
  if (report.issues.size() < options.max_issues) {
    report.issues.push_back({line, kind, std::move(detail)});
  }
}

ENDOHAPTICS_DECL std::string where(const Layout& layout, const std::string& path,
                                   std::size_t line) {
  return std::string(layout.function) + ": " + path + ":" + std::to_string(line) + ": ";
}

ENDOHAPTICS_DECL Rows parse_rows(Lines& lines, const Layout& layout, const LogReadOptions& options,
                                 LogReport& report) {
  const std::size_t columns = layout.labels.size();
  Rows rows;
  std::vector<double> row(columns);
  std::size_t ordinal = 0;
  for (const log_text::Line* next = lines.next(); next != nullptr; next = lines.next(), ++ordinal) {
    const log_text::Line& line = *next;
    const auto fields = split(line.text, layout.separator);
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

ENDOHAPTICS_DECL Rows read_rows(Lines& lines, const Layout& layout, const LogReadOptions& options,
                                LogReport& report) {
  if (!std::isfinite(options.gap_threshold) || options.gap_threshold < 0) {
    ENDOHAPTICS_THROW(Error(std::string(layout.function) +
                            ": gap_threshold must be finite and >= 0, got " +
                            format(options.gap_threshold)));
  }
  Rows rows = parse_rows(lines, layout, options, report);
  report.lines = lines.total_lines();
  report.crlf_lines = lines.crlf_lines();
  report.blank_lines = lines.blank_lines();
  report.byte_order_mark = lines.byte_order_mark();
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

ENDOHAPTICS_DECL LogReport start_report(const std::string& path) {
  LogReport report;
  report.source = path;
  return report;
}

ENDOHAPTICS_DECL Eigen::VectorXd column_of(const Rows& rows, std::size_t columns, std::size_t c) {
  const auto n = static_cast<Eigen::Index>(rows.time.size());
  Eigen::VectorXd v(n);
  for (Eigen::Index r = 0; r < n; ++r)
    v[r] = rows.values[static_cast<std::size_t>(r) * columns + c];
  return v;
}

}  // namespace detail::log_rows

}  // namespace endohaptics::files
