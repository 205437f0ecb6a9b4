//! @file
//! Function bodies of files/csv_log.hpp: included at its end (header-only, the default), or
//! compiled once with ENDOHAPTICS_SEPARATE_COMPILATION (core/separate_compilation.hpp).
#pragma once

#include "endohaptics/files/csv_log.hpp"

namespace endohaptics::files {

ENDOHAPTICS_DECL Log read_csv(const std::string& path, const CsvOptions& options) {
  namespace lt = detail::log_text;
  namespace lr = detail::log_rows;
  constexpr std::string_view fn = "read_csv";
  lt::Lines lines(path, fn, options.read.max_bytes);
  LogReport report = lr::start_report(path);
  if (lines.peek() == nullptr) {
    ENDOHAPTICS_THROW(Error(std::string(fn) + ": " + path + ": no usable rows (file is empty)"));
  }
  if (options.separator != '\0' && options.separator != ',' && options.separator != ';' &&
      options.separator != '\t' && options.separator != ' ') {
    ENDOHAPTICS_THROW(Error(std::string(fn) + ": separator must be ',', ';', tab or blank, got '" +
                            std::string(1, options.separator) + "'"));
  }
  const lt::Line head = *lines.peek();
  const char separator =
      options.separator != '\0' ? options.separator : lt::detect_separator(head.text);
  const bool has_header = lt::looks_like_header(head.text, separator);
  std::vector<std::string> names;
  if (!options.column_names.empty()) {
    names = options.column_names;
  } else if (has_header) {
    for (std::string_view field : lt::split(head.text, separator)) {
      if (field.size() >= 2 && field.front() == '"' && field.back() == '"') {
        field = lt::trim(field.substr(1, field.size() - 2));
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
  if (has_header) (void)lines.next();
  const lr::Rows rows = lr::read_rows(lines, layout, options.read, report);

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

}  // namespace endohaptics::files
