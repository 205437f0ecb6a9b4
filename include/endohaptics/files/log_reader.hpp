//! @file
//! Readers for measurement logs used in system identification: the 2016 EndoWrist logs
//! (worksheet appendix E; ../shared/data/endowrist-2016/README.md: time s, load-cell V, force kN
//! -> N, setpoint/position rad, currents A; friction logs: time, encoder ticks, current A) and
//! generic headed CSV. Every dropped or repaired line is counted in a LogReport. Configuration
//! time: allocates, throws endohaptics::Error naming file, line and field.
#pragma once

#include <Eigen/Core>
#include <algorithm>
#include <charconv>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <limits>
#include <map>
#include <numbers>
#include <sstream>
#include <string>
#include <string_view>
#include <system_error>
#include <vector>

#include "endohaptics/core/error.hpp"
#include "endohaptics/identification/signal.hpp"

namespace endohaptics::files {

//! What to do with a row that cannot be used.
enum class OnBadRow : std::uint8_t {
  drop,         //!< skip it, count it in the report
  throw_error,  //!< throw endohaptics::Error naming file, line and field
};

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

//! A log: named signals sampled at `time`, plus the report of what was dropped or repaired.
struct Log {
  std::string source;              //!< the file read
  std::vector<std::string> names;  //!< one per column of `data` ("time" is not a column)
  std::vector<std::string> units;  //!< one per column ("" when unknown)
  Eigen::VectorXd time;            //!< s, strictly increasing (rebased: starts at 0)
  Eigen::MatrixXd data;            //!< rows: samples, columns: signals in `names` order
  LogReport report;                //!< what the reader dropped, repaired, found

  //! Number of samples (rows of `data`, entries of `time`).
  [[nodiscard]] Eigen::Index rows() const noexcept { return time.size(); }

  //! True for "time" and for every name in `names`.
  [[nodiscard]] bool has(std::string_view name) const {
    return name == "time" || std::find(names.begin(), names.end(), name) != names.end();
  }

  //! Column of `name` in `data`. Throws Error naming the file and the available signals.
  [[nodiscard]] Eigen::Index column(std::string_view name) const {
    const auto it = std::find(names.begin(), names.end(), name);
    if (it == names.end()) {
      std::string known = "time";
      for (const auto& n : names) known += ", " + n;
      ENDOHAPTICS_THROW(Error("Log: " + source + ": no signal named '" + std::string(name) +
                              "' (signals: " + known + ")"));
    }
    return static_cast<Eigen::Index>(it - names.begin());
  }

  //! The samples of one signal ("time" gives `time`). Throws Error for an unknown name.
  [[nodiscard]] Eigen::VectorXd signal(std::string_view name) const {
    if (name == "time") return time;
    return data.col(column(name));
  }

  //! The named signals as columns, in the order given. Throws Error for an unknown name.
  [[nodiscard]] Eigen::MatrixXd select(const std::vector<std::string>& selected) const {
    Eigen::MatrixXd out(rows(), static_cast<Eigen::Index>(selected.size()));
    for (std::size_t i = 0; i < selected.size(); ++i) {
      out.col(static_cast<Eigen::Index>(i)) = signal(selected[i]);
    }
    return out;
  }
};

namespace detail::log_reader {

using identification::detail::signal::format;

//! Ten significant digits: enough for the logs' time stamps, short enough to read.
inline std::string readable(double value) {
  std::ostringstream out;
  out.precision(10);
  out << value;
  return out.str();
}

//! The file's text, split into lines (offsets into `content`, CR of CR LF removed).
struct Text {
  struct Line {
    std::size_t number = 0;  //!< 1-based
    std::size_t begin = 0;
    std::size_t length = 0;
  };
  std::string content;
  std::vector<Line> lines;  //!< non-blank lines only
  std::size_t total_lines = 0;
  std::size_t crlf_lines = 0;
  std::size_t blank_lines = 0;
  bool byte_order_mark = false;

  [[nodiscard]] std::string_view text(const Line& line) const {
    return std::string_view(content).substr(line.begin, line.length);
  }
};

inline std::string_view trim(std::string_view s) {
  const auto first = s.find_first_not_of(" \t");
  if (first == std::string_view::npos) return {};
  const auto last = s.find_last_not_of(" \t");
  return s.substr(first, last - first + 1);
}

inline Text read_text(const std::string& path, std::string_view function) {
  std::error_code ec;
  if (!std::filesystem::exists(path, ec)) {
    ENDOHAPTICS_THROW(Error(std::string(function) + ": " + path + ": file does not exist"));
  }
  if (std::filesystem::is_directory(path, ec)) {
    ENDOHAPTICS_THROW(Error(std::string(function) + ": " + path + ": is a directory"));
  }
  std::ifstream in(path, std::ios::binary);
  if (!in) ENDOHAPTICS_THROW(Error(std::string(function) + ": " + path + ": cannot be opened"));
  Text t;
  t.content.assign(std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>());
  if (in.bad()) ENDOHAPTICS_THROW(Error(std::string(function) + ": " + path + ": read error"));
  std::size_t pos = 0;
  if (t.content.starts_with("\xEF\xBB\xBF")) {
    t.byte_order_mark = true;
    pos = 3;
  }
  std::size_t number = 0;
  while (pos < t.content.size()) {
    std::size_t end = t.content.find('\n', pos);
    const bool terminated = end != std::string::npos;
    if (!terminated) end = t.content.size();
    std::size_t length = end - pos;
    ++number;
    if (terminated && length > 0 && t.content[end - 1] == '\r') {
      ++t.crlf_lines;
      --length;
    }
    const std::string_view line = std::string_view(t.content).substr(pos, length);
    if (trim(line).empty()) {
      ++t.blank_lines;
    } else {
      t.lines.push_back({number, pos, length});
    }
    pos = end + 1;
  }
  t.total_lines = number;
  return t;
}

//! Fields of a line: split at `separator` (' ' = runs of blanks and tabs), each trimmed.
inline std::vector<std::string_view> split(std::string_view line, char separator) {
  std::vector<std::string_view> fields;
  if (separator == ' ' || separator == '\t') {
    std::size_t pos = 0;
    while (true) {
      pos = line.find_first_not_of(" \t", pos);
      if (pos == std::string_view::npos) break;
      const std::size_t end = std::min(line.find_first_of(" \t", pos), line.size());
      fields.push_back(line.substr(pos, end - pos));
      pos = end;
    }
    return fields;
  }
  std::size_t pos = 0;
  while (true) {
    const std::size_t end = line.find(separator, pos);
    fields.push_back(trim(line.substr(pos, end == std::string_view::npos ? end : end - pos)));
    if (end == std::string_view::npos) break;
    pos = end + 1;
  }
  return fields;
}

enum class Number : std::uint8_t { ok, empty, non_numeric, non_finite };

//! Locale-independent parse of a whole field as a double.
inline Number parse_number(std::string_view field, double& value) {
  if (field.empty()) return Number::empty;
  std::string_view s = field;
  if (s.size() > 1 && s.front() == '+' && s[1] != '-' && s[1] != '+') s.remove_prefix(1);
  const char* first = s.data();
  const char* last = s.data() + s.size();
  double v = 0;
  const auto [ptr, ec] = std::from_chars(first, last, v);
  if (ptr != last || ec == std::errc::invalid_argument) return Number::non_numeric;
  if (ec == std::errc::result_out_of_range) {
    // Underflow (e.g. 1e-400) reads as 0; overflow is not finite.
    const auto e = s.find_first_of("eE");
    if (e != std::string_view::npos && e + 1 < s.size() && s[e + 1] == '-') {
      value = 0.0;
      return Number::ok;
    }
    return Number::non_finite;
  }
  value = v;
  return std::isfinite(v) ? Number::ok : Number::non_finite;
}

inline bool looks_like_header(std::string_view line, char separator) {
  const auto fields = split(line, separator);
  double v = 0;
  return !fields.empty() && parse_number(fields.front(), v) == Number::non_numeric;
}

//! Detects the separator of a line: ';' if present, else ',' if present, else blanks.
inline char detect_separator(std::string_view line) {
  if (line.find(';') != std::string_view::npos) return ';';
  if (line.find(',') != std::string_view::npos) return ',';
  return ' ';
}

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

}  // namespace detail::log_reader

// ---------------------------------------------------------------------------------------------
// EndoWrist 2016 logs

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
[[nodiscard]] inline Log read_endowrist_2016(const std::string& path,
                                             const Endowrist2016Options& options = {}) {
  namespace lr = detail::log_reader;
  constexpr std::string_view fn = "read_endowrist_2016";
  const lr::Text text = lr::read_text(path, fn);
  LogReport report = lr::start_report(text, path);
  if (text.lines.empty()) {
    ENDOHAPTICS_THROW(Error(std::string(fn) + ": " + path + ": no usable rows (file is empty)"));
  }
  std::size_t first = 0;
  if (lr::looks_like_header(text.text(text.lines.front()), ',')) {
    report.header = true;
    first = 1;
  }

  Endowrist2016Layout layout = options.layout;
  if (layout == Endowrist2016Layout::detect) {
    std::map<std::size_t, std::size_t> counts;
    for (std::size_t i = first; i < std::min(text.lines.size(), first + 20); ++i) {
      ++counts[lr::split(text.text(text.lines[i]), ',').size()];
    }
    std::size_t fields = 0;
    std::size_t seen = 0;
    for (const auto& [n, c] : counts) {
      if (c > seen) {
        fields = n;
        seen = c;
      }
    }
    if (fields >= 7) {
      layout = Endowrist2016Layout::measurement;
    } else if (fields == 3 || fields == 4) {
      layout = Endowrist2016Layout::friction;
    } else {
      const std::size_t line =
          first < text.lines.size() ? text.lines[first].number : text.lines.front().number;
      ENDOHAPTICS_THROW(Error(std::string(fn) + ": " + path + ":" + std::to_string(line) +
                              ": cannot tell the log layout: most lines have " +
                              std::to_string(fields) +
                              " fields (7: measurement log, 3: friction log)"));
    }
  }
  if (!std::isfinite(options.force_scale) || !std::isfinite(options.radians_per_tick) ||
      !std::isfinite(options.force_per_volt) || !std::isfinite(options.force_tolerance)) {
    ENDOHAPTICS_THROW(Error(std::string(fn) + ": scale options must be finite"));
  }

  const bool measurement = layout == Endowrist2016Layout::measurement;
  lr::Layout rows_layout;
  rows_layout.function = fn;
  rows_layout.labels =
      measurement
          ? std::vector<std::string>{"time",     "loadcell_voltage", "force",         "setpoint",
                                     "position", "current",          "current_demand"}
          : std::vector<std::string>{"time", "ticks", "current"};
  const std::size_t columns = rows_layout.labels.size();
  const lr::Rows rows = lr::read_rows(text, first, rows_layout, options.read, report);

  Log log;
  log.source = path;
  log.time = Eigen::Map<const Eigen::VectorXd>(rows.time.data(),
                                               static_cast<Eigen::Index>(rows.time.size()));
  const Eigen::Index n = log.time.size();
  if (measurement) {
    log.names = {"loadcell_voltage", "force",          "setpoint", "position",
                 "current",          "current_demand", "velocity"};
    log.units = {"V", "N", "rad", "rad", "A", "A", "rad/s"};
    log.data.resize(n, 7);
    for (std::size_t c = 1; c < columns; ++c) {
      log.data.col(static_cast<Eigen::Index>(c - 1)) = lr::column_of(rows, columns, c);
    }
    log.data.col(1) *= options.force_scale;
    if (options.force_per_volt != 0) {
      for (Eigen::Index r = 0; r < n; ++r) {
        const double expected = options.force_per_volt * log.data(r, 0);
        if (std::abs(log.data(r, 1) - expected) > options.force_tolerance) {
          ++report.force_mismatch;
          lr::record(
              report, options.read, rows.line[static_cast<std::size_t>(r)],
              LogIssueKind::force_mismatch,
              lr::readable(log.data(r, 1)) + " N, voltage gives " + lr::readable(expected) + " N");
        }
      }
      std::stable_sort(report.issues.begin(), report.issues.end(),
                       [](const LogIssue& a, const LogIssue& b) { return a.line < b.line; });
    }
  } else {
    log.names = {"ticks", "position", "current", "velocity"};
    log.units = {"", "rad", "A", "rad/s"};
    log.data.resize(n, 4);
    log.data.col(0) = lr::column_of(rows, columns, 1);
    log.data.col(1) = log.data.col(0) * options.radians_per_tick;
    log.data.col(2) = lr::column_of(rows, columns, 2);
  }
  const Eigen::Index position = measurement ? 3 : 1;
  const double max_gap =
      report.gap_threshold > 0 ? report.gap_threshold : std::numeric_limits<double>::max();
  log.data.col(log.data.cols() - 1) =
      identification::differentiate(log.time, log.data.col(position), max_gap);
  log.report = std::move(report);
  return log;
}

// ---------------------------------------------------------------------------------------------
// Generic CSV

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
[[nodiscard]] inline Log read_csv(const std::string& path, const CsvOptions& options = {}) {
  namespace lr = detail::log_reader;
  constexpr std::string_view fn = "read_csv";
  const lr::Text text = lr::read_text(path, fn);
  LogReport report = lr::start_report(text, path);
  if (text.lines.empty()) {
    ENDOHAPTICS_THROW(Error(std::string(fn) + ": " + path + ": no usable rows (file is empty)"));
  }
  if (options.separator != '\0' && options.separator != ',' && options.separator != ';' &&
      options.separator != '\t' && options.separator != ' ') {
    ENDOHAPTICS_THROW(Error(std::string(fn) + ": separator must be ',', ';', tab or blank, got '" +
                            std::string(1, options.separator) + "'"));
  }
  const auto& head = text.lines.front();
  const char separator =
      options.separator != '\0' ? options.separator : lr::detect_separator(text.text(head));
  const bool has_header = lr::looks_like_header(text.text(head), separator);
  std::vector<std::string> names;
  if (!options.column_names.empty()) {
    names = options.column_names;
  } else if (has_header) {
    for (std::string_view field : lr::split(text.text(head), separator)) {
      if (field.size() >= 2 && field.front() == '"' && field.back() == '"') {
        field = lr::trim(field.substr(1, field.size() - 2));
      }
      names.emplace_back(field);
    }
  } else {
    ENDOHAPTICS_THROW(Error(std::string(fn) + ": " + path + ":" + std::to_string(head.number) +
                            ": expected a header line naming the columns, found numbers (give "
                            "CsvOptions::column_names for a file without header)"));
  }
  report.header = has_header;
  for (std::size_t i = 0; i < names.size(); ++i) {
    if (names[i].empty()) {
      ENDOHAPTICS_THROW(Error(std::string(fn) + ": " + path + ":" + std::to_string(head.number) +
                              ": column " + std::to_string(i + 1) + " has no name"));
    }
    for (std::size_t j = 0; j < i; ++j) {
      if (names[j] == names[i]) {
        ENDOHAPTICS_THROW(Error(std::string(fn) + ": " + path + ":" + std::to_string(head.number) +
                                ": column " + std::to_string(i + 1) + " repeats the name '" +
                                names[i] + "'"));
      }
    }
  }
  std::ptrdiff_t time_column = -1;
  const std::string wanted = options.time_column.empty() ? "time" : options.time_column;
  if (const auto it = std::find(names.begin(), names.end(), wanted); it != names.end()) {
    time_column = it - names.begin();
  } else if (!options.time_column.empty()) {
    std::string known;
    for (const auto& n : names) known += (known.empty() ? "" : ", ") + n;
    ENDOHAPTICS_THROW(Error(std::string(fn) + ": " + path + ":" + std::to_string(head.number) +
                            ": no column named '" + options.time_column +
                            "' for time (columns: " + known + ")"));
  }
  if (time_column < 0) {
    identification::detail::signal::require_positive(options.sample_time, fn, "sample_time");
  }

  lr::Layout layout;
  layout.function = fn;
  layout.labels = names;
  layout.separator = separator;
  layout.time_column = time_column;
  layout.sample_time = options.sample_time;
  const lr::Rows rows = lr::read_rows(text, has_header ? 1 : 0, layout, options.read, report);

  Log log;
  log.source = path;
  log.time = Eigen::Map<const Eigen::VectorXd>(rows.time.data(),
                                               static_cast<Eigen::Index>(rows.time.size()));
  log.data.resize(log.time.size(),
                  static_cast<Eigen::Index>(names.size()) - (time_column >= 0 ? 1 : 0));
  Eigen::Index out = 0;
  for (std::size_t c = 0; c < names.size(); ++c) {
    if (static_cast<std::ptrdiff_t>(c) == time_column) continue;
    log.names.push_back(names[c]);
    log.units.emplace_back();
    log.data.col(out++) = lr::column_of(rows, names.size(), c);
  }
  log.report = std::move(report);
  return log;
}

// ---------------------------------------------------------------------------------------------
// Format by name (for command lines)

//! The log formats a command line can name.
enum class LogFormat : std::uint8_t {
  endowrist_2016,  //!< "endowrist-2016": read_endowrist_2016 with default options
  csv,             //!< "csv": read_csv with default options
};

//! Parses "endowrist-2016" or "csv". Throws Error naming the value and the valid ones.
[[nodiscard]] inline LogFormat parse_log_format(std::string_view name) {
  if (name == "endowrist-2016") return LogFormat::endowrist_2016;
  if (name == "csv") return LogFormat::csv;
  ENDOHAPTICS_THROW(
      Error("unknown log format '" + std::string(name) + "' (valid: endowrist-2016, csv)"));
}

//! Reads `path` in `format` with the shared policies `read`.
[[nodiscard]] inline Log read_log(const std::string& path, LogFormat format,
                                  const LogReadOptions& read = {}) {
  if (format == LogFormat::endowrist_2016) {
    Endowrist2016Options o;
    o.read = read;
    return read_endowrist_2016(path, o);
  }
  CsvOptions o;
  o.read = read;
  return read_csv(path, o);
}

}  // namespace endohaptics::files
