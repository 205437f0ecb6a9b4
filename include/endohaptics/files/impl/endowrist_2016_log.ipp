//! @file
//! Function bodies of files/endowrist_2016_log.hpp: included at its end (header-only, the default),
//! or compiled once with ENDOHAPTICS_SEPARATE_COMPILATION (core/separate_compilation.hpp).
#pragma once

#include "endohaptics/files/endowrist_2016_log.hpp"

namespace endohaptics::files {

ENDOHAPTICS_DECL Log read_endowrist_2016(const std::string& path,
                                         const Endowrist2016Options& options) {
  namespace lt = detail::log_text;
  namespace lr = detail::log_rows;
  constexpr std::string_view fn = "read_endowrist_2016";
  lt::Lines lines(path, fn, options.read.max_bytes);
  LogReport report = lr::start_report(path);
  if (lines.peek() == nullptr) {
    ENDOHAPTICS_THROW(Error(std::string(fn) + ": " + path + ": no usable rows (file is empty)"));
  }
  std::size_t first = 0;
  if (lt::looks_like_header(lines.peek()->text, ',')) {
    report.header = true;
    first = 1;
  }

  Endowrist2016Layout layout = options.layout;
  if (layout == Endowrist2016Layout::detect) {
    std::map<std::size_t, std::size_t> counts;
    for (std::size_t i = first; i < first + 20 && lines.peek(i) != nullptr; ++i) {
      ++counts[lt::split(lines.peek(i)->text, ',').size()];
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
          lines.peek(first) != nullptr ? lines.peek(first)->number : lines.peek()->number;
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
  if (report.header) (void)lines.next();
  const lr::Rows rows = lr::read_rows(lines, rows_layout, options.read, report);

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
              lt::readable(log.data(r, 1)) + " N, voltage gives " + lt::readable(expected) + " N");
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

}  // namespace endohaptics::files
