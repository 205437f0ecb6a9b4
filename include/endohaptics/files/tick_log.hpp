//! @file
//! Reader of the bridge's per-tick CSV log (teleop::TickRecorder): columns are found by their
//! header names (teleop::tick_log_columns), never by position, so a reader keeps working when
//! columns are added or reordered. Malformed lines (wrong field count, a field that is not a
//! number, e.g. a row cut short when the bridge was killed, a time not after the previous row's)
//! are dropped and counted, or refused. A file is read line by line (files/log_text.hpp: a
//! regular file of at most TickLogOptions::max_bytes), never held whole.
#pragma once

#include <algorithm>
#include <charconv>
#include <chrono>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <filesystem>
#include <istream>
#include <string>
#include <string_view>
#include <system_error>
#include <utility>
#include <vector>

#include "endohaptics/core/error.hpp"
#include "endohaptics/files/log_text.hpp"
#include "endohaptics/teleop/loop_stats.hpp"
#include "endohaptics/teleop/tick_recorder.hpp"

namespace endohaptics::files {

namespace detail::tick_log {

//! At most `max` characters of `text`, with "..." when cut.
inline std::string excerpt(std::string_view text, std::size_t max = 60) {
  std::string out(text.substr(0, max));
  for (char& c : out) {
    if (static_cast<unsigned char>(c) < 0x20) c = '?';
  }
  return text.size() > max ? out + "..." : out;
}

//! The comma-separated fields of `line` (no quoting: the tick log has none).
inline std::vector<std::string_view> split(std::string_view line) {
  std::vector<std::string_view> fields;
  std::size_t start = 0;
  for (;;) {
    const std::size_t comma = line.find(',', start);
    fields.push_back(line.substr(start, comma == std::string_view::npos ? comma : comma - start));
    if (comma == std::string_view::npos) return fields;
    start = comma + 1;
  }
}

//! Parses a whole field as a double ("nan" and "inf" as the recorder writes them); false if not.
inline bool parse(std::string_view field, double& value) {
  while (!field.empty() && field.front() == ' ') field.remove_prefix(1);
  while (!field.empty() && field.back() == ' ') field.remove_suffix(1);
  if (field.empty()) return false;
  if (field.front() == '+') field.remove_prefix(1);
  const auto [end, error] = std::from_chars(field.data(), field.data() + field.size(), value);
  return error == std::errc() && end == field.data() + field.size();
}

}  // namespace detail::tick_log

//! How `read_tick_log` treats a malformed line.
struct TickLogOptions {
  bool strict = false;          //!< true: a malformed line is an error; false: dropped, counted
  std::size_t max_issues = 20;  //!< dropped lines described in `TickLog::issues` (all counted)
  //! A row whose "time" is not after the previous row's is malformed (the recorder's times
  //! increase; a repeated or backward time means a corrupt log). No effect without "time".
  bool increasing_time = true;
  //! Largest file read_tick_log reads, bytes: a larger one (or one that grows beyond it while
  //! being read) is refused, naming the file, its size and this option.
  std::uint64_t max_bytes = default_log_max_bytes;
};

//! One dropped line: where and why.
struct TickLogIssue {
  std::size_t line = 0;  //!< 1-based line number in the file (the header is line 1)
  std::string what;      //!< e.g. "12 fields, the header has 30"
};

//! A tick log in memory: the header's column names and one vector of values per column.
class TickLog {
 public:
  std::string source;                //!< file name (or the name given to parse_tick_log)
  std::vector<std::string> columns;  //!< header names, in file order
  std::size_t dropped = 0;           //!< malformed lines left out (blank lines are not counted)
  std::vector<TickLogIssue> issues;  //!< the first TickLogOptions::max_issues dropped lines

  //! Number of rows read (every column has this many values).
  [[nodiscard]] std::size_t rows() const noexcept { return data_.empty() ? 0 : data_[0].size(); }

  //! True when the header has a column `name`.
  [[nodiscard]] bool has(std::string_view name) const noexcept {
    return std::find(columns.begin(), columns.end(), name) != columns.end();
  }

  //! 0-based position of column `name`. Throws Error naming the file, the column and the header.
  [[nodiscard]] std::size_t index(std::string_view name) const {
    const auto it = std::find(columns.begin(), columns.end(), name);
    if (it == columns.end()) {
      std::string header;
      for (const auto& c : columns) header += (header.empty() ? "" : ",") + c;
      if (header.size() > 200) header = header.substr(0, 200) + "...";
      ENDOHAPTICS_THROW(Error(source + ": no column '" + detail::tick_log::excerpt(name) +
                              "' in the tick log (header: " + header + ")"));
    }
    return static_cast<std::size_t>(it - columns.begin());
  }

  //! The values of column `name`, one per row. Throws Error as `index`.
  [[nodiscard]] const std::vector<double>& column(std::string_view name) const {
    return data_[index(name)];
  }

  //! "<n> malformed lines dropped" and the first issues, one per line; empty when none.
  [[nodiscard]] std::string report() const {
    if (dropped == 0) return {};
    std::string out = source + ": " + std::to_string(dropped) + " malformed line" +
                      (dropped == 1 ? "" : "s") + " dropped\n";
    for (const auto& i : issues) out += "  line " + std::to_string(i.line) + ": " + i.what + "\n";
    if (issues.size() < dropped) {
      out += "  (" + std::to_string(dropped - issues.size()) + " more)\n";
    }
    return out;
  }

  //! Appends one row; `values` has one entry per column. For `parse_tick_log`.
  void append(const std::vector<double>& values) {
    ENDOHAPTICS_ASSERT(values.size() == columns.size());
    if (data_.size() != columns.size()) data_.assign(columns.size(), {});
    for (std::size_t c = 0; c < values.size(); ++c) data_[c].push_back(values[c]);
  }

 private:
  std::vector<std::vector<double>> data_;
};

namespace detail::tick_log {

//! parse_tick_log on the lines that `next_line(std::string&)` gives one at a time (false at the
//! end), as std::getline gives them; `number` counts them.
template <typename NextLine>
[[nodiscard]] TickLog parse_lines(NextLine&& next_line, std::string source,
                                  const TickLogOptions& options, std::size_t& number) {
  TickLog log;
  log.source = std::move(source);
  std::string line;
  number = 0;
  if (!next_line(line)) {
    ENDOHAPTICS_THROW(Error(log.source + ": empty, expected the tick-log header (" +
                            std::string(teleop::tick_log_columns[0]) + "," +
                            std::string(teleop::tick_log_columns[1]) + ",...)"));
  }
  number = 1;
  if (!line.empty() && line.back() == '\r') line.pop_back();
  for (const auto name : split(line)) {
    if (name.empty()) {
      ENDOHAPTICS_THROW(Error(log.source + ": line 1: empty column name in the header"));
    }
    if (log.has(name)) {
      ENDOHAPTICS_THROW(Error(log.source + ": line 1: column '" + excerpt(name) +
                              "' appears twice in the header"));
    }
    log.columns.emplace_back(name);
  }
  std::vector<double> values(log.columns.size());
  const auto time_at = std::find(log.columns.begin(), log.columns.end(), "time");
  const auto time_column = static_cast<std::size_t>(time_at - log.columns.begin());
  const bool check_time = options.increasing_time && time_at != log.columns.end();
  double last_time = 0.0;
  bool have_time = false;
  auto drop = [&](std::string what) {
    if (options.strict) {
      ENDOHAPTICS_THROW(Error(log.source + ": line " + std::to_string(number) + ": " + what));
    }
    ++log.dropped;
    if (log.issues.size() < options.max_issues) log.issues.push_back({number, std::move(what)});
  };
  while (next_line(line)) {
    ++number;
    if (!line.empty() && line.back() == '\r') line.pop_back();
    if (line.find_first_not_of(" \t") == std::string::npos) continue;  // blank line
    const auto fields = split(line);
    if (fields.size() != log.columns.size()) {
      drop(std::to_string(fields.size()) + " fields, the header has " +
           std::to_string(log.columns.size()));
      continue;
    }
    bool ok = true;
    for (std::size_t c = 0; c < fields.size() && ok; ++c) {
      ok = parse(fields[c], values[c]);
      if (!ok) {
        drop("column '" + excerpt(log.columns[c]) + "': not a number: '" + excerpt(fields[c]) +
             "'");
      }
    }
    if (ok && check_time) {
      const double t = values[time_column];
      if (have_time && !(t > last_time)) {
        drop("time " + endohaptics::detail::format_number(t) + " is not after " +
             endohaptics::detail::format_number(last_time));
        continue;
      }
      last_time = t;
      have_time = true;
    }
    if (ok) log.append(values);
  }
  return log;
}

}  // namespace detail::tick_log

//! Reads a tick log from `in` (its first line is the header). `source` names it in messages.
//! Throws Error on a missing or malformed header (empty, duplicate or empty names), on an I/O
//! error, and with `options.strict` on the first malformed line; otherwise malformed lines are
//! dropped and counted in `TickLog::dropped` / `issues`. (`options.max_bytes` is read_tick_log's.)
[[nodiscard]] inline TickLog parse_tick_log(std::istream& in, std::string source,
                                            const TickLogOptions& options = {}) {
  std::size_t number = 0;
  TickLog log = detail::tick_log::parse_lines(
      [&in](std::string& line) { return static_cast<bool>(std::getline(in, line)); },
      std::move(source), options, number);
  if (in.bad())
    ENDOHAPTICS_THROW(Error(log.source + ": read error after line " + std::to_string(number)));
  return log;
}

//! Reads the tick log file `path` (teleop::TickRecorder's CSV) line by line: a regular file of at
//! most `options.max_bytes` (a FIFO or device is refused without blocking). Throws Error as
//! parse_tick_log, or naming the file when it cannot be opened, is not a regular file or is
//! larger than the limit.
[[nodiscard]] inline TickLog read_tick_log(const std::filesystem::path& path,
                                           const TickLogOptions& options = {}) {
  detail::log_text::LineReader reader(path.string(), "tick log", options.max_bytes,
                                      "raise TickLogOptions::max_bytes to read it");
  std::size_t number = 0;
  return detail::tick_log::parse_lines([&reader](std::string& line) { return reader.next(line); },
                                       path.string(), options, number);
}

//! Tick-to-tick periods of a tick log as LoopStats (its `period()` histogram, quantiles, mean,
//! max and `rate()`), from the "time" column in s. The log's times are taken as each tick ended,
//! so these are end-to-end periods. `nominal` as in LoopStats (0: no deadline figures).
[[nodiscard]] inline teleop::LoopStats tick_period_stats(
    const TickLog& log, std::chrono::nanoseconds nominal = std::chrono::nanoseconds(0)) {
  teleop::LoopStats stats(nominal);
  for (const double t : log.column("time")) {
    if (!std::isfinite(t) || std::fabs(t) > 9e9) {  // ~285 years of ns fit in int64
      ENDOHAPTICS_THROW(Error(log.source + ": time is not a finite time in s: " +
                              endohaptics::detail::format_number(t)));
    }
    stats.record_tick_start(std::chrono::nanoseconds(std::llround(t * 1e9)));
  }
  return stats;
}

}  // namespace endohaptics::files
