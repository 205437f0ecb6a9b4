//! @file
//! What a log reader kept, dropped and repaired: the defect kinds (LogIssueKind), the defects
//! recorded with their 1-based line (LogIssue) and the counts per reason, time steps in s
//! (LogReport), with a printable summary.
#pragma once

#include <cstddef>
#include <cstdint>
#include <limits>
#include <sstream>
#include <string>
#include <string_view>
#include <vector>

namespace endohaptics::files {

//! Kinds of defects a reader records (with their line) in `LogReport::issues`.
enum class LogIssueKind : std::uint8_t {
  empty_field,     //!< dropped: a field is empty
  short_line,      //!< dropped: fewer fields than columns
  non_numeric,     //!< dropped: a field is not a number
  non_finite,      //!< dropped: NaN, Inf or out of double range
  repeated_time,   //!< dropped: same time stamp as the previous kept row
  backward_time,   //!< dropped: time stamp before the previous kept row
  extra_fields,    //!< kept: fields beyond the known columns ignored
  gap,             //!< kept: time step above the gap threshold before this row
  force_mismatch,  //!< kept: logged force disagrees with force_per_volt x load-cell voltage
};

//! Short name of an issue kind.
[[nodiscard]] constexpr std::string_view to_string(LogIssueKind kind) noexcept {
  switch (kind) {
    case LogIssueKind::empty_field:
      return "empty field";
    case LogIssueKind::short_line:
      return "short line";
    case LogIssueKind::non_numeric:
      return "non-numeric field";
    case LogIssueKind::non_finite:
      return "non-finite value";
    case LogIssueKind::repeated_time:
      return "repeated time stamp";
    case LogIssueKind::backward_time:
      return "backward time stamp";
    case LogIssueKind::extra_fields:
      return "extra fields ignored";
    case LogIssueKind::gap:
      return "time gap";
    case LogIssueKind::force_mismatch:
      return "force/voltage mismatch";
  }
  return "unknown issue";
}

//! One recorded defect: 1-based line number in the file, kind, and what was found.
struct LogIssue {
  std::size_t line = 0;                           //!< 1-based line in the file
  LogIssueKind kind = LogIssueKind::non_numeric;  //!< what kind of defect
  std::string detail;                             //!< e.g. "field 3 (force): 'abc'"
};

//! What a reader kept, dropped and repaired. Each dropped row is counted under one reason.
struct LogReport {
  std::string source;             //!< the file read
  std::size_t lines = 0;          //!< physical lines in the file (header and blank included)
  std::size_t rows = 0;           //!< rows kept
  bool header = false;            //!< a header line was found (and skipped or used for names)
  bool byte_order_mark = false;   //!< a UTF-8 byte order mark was removed
  std::size_t crlf_lines = 0;     //!< lines that ended in CR LF (the CR removed)
  std::size_t blank_lines = 0;    //!< empty or whitespace-only lines skipped
  std::size_t empty_fields = 0;   //!< rows dropped: a field is empty
  std::size_t short_lines = 0;    //!< rows dropped: fewer fields than columns
  std::size_t non_numeric = 0;    //!< rows dropped: a field is not a number
  std::size_t non_finite = 0;     //!< rows dropped: NaN, Inf or a value out of double range
  std::size_t repeated_time = 0;  //!< rows dropped: time equal to the previous kept row
  std::size_t backward_time = 0;  //!< rows dropped: time before the previous kept row
  std::size_t extra_fields = 0;   //!< rows kept whose fields beyond the columns were ignored
  std::size_t gaps = 0;           //!< kept time steps > gap_threshold (data kept; see resample)
  double largest_step = 0;        //!< largest kept time step, s
  double gap_threshold = 0;       //!< the threshold used, s
  double median_step = std::numeric_limits<double>::quiet_NaN();  //!< s
  double time_offset = 0;          //!< s subtracted from the file's time stamps (first kept stamp)
  std::size_t force_mismatch = 0;  //!< EndoWrist: rows whose force != force_per_volt x voltage
  std::vector<LogIssue> issues;    //!< the first max_issues defects, by line

  //! Rows dropped, all reasons.
  [[nodiscard]] std::size_t dropped() const noexcept {
    return empty_fields + short_lines + non_numeric + non_finite + repeated_time + backward_time;
  }

  //! Multi-line summary for a terminal or a log file.
  [[nodiscard]] std::string to_string() const {
    std::ostringstream out;
    out.precision(10);
    out << source << ": " << rows << " rows kept from " << lines << " lines"
        << (header ? "; header line" : "; no header line") << "; CRLF " << crlf_lines << "; blank "
        << blank_lines << (byte_order_mark ? "; byte order mark removed" : "") << '\n';
    out << "  dropped " << dropped() << ": empty field " << empty_fields << ", short line "
        << short_lines << ", non-numeric " << non_numeric << ", non-finite " << non_finite
        << ", repeated time " << repeated_time << ", backward time " << backward_time << '\n';
    out << "  kept with extra fields ignored " << extra_fields << "; force/voltage mismatch "
        << force_mismatch << '\n';
    out << "  time: rebased by " << time_offset << " s; median step " << median_step
        << " s; gaps > " << gap_threshold << " s: " << gaps << " (largest step " << largest_step
        << " s)\n";
    for (const LogIssue& issue : issues) {
      out << "  line " << issue.line << ": " << files::to_string(issue.kind);
      if (!issue.detail.empty()) out << ": " << issue.detail;
      out << '\n';
    }
    return out.str();
  }
};

}  // namespace endohaptics::files
