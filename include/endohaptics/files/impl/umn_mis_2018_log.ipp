//! @file
//! Function bodies of files/umn_mis_2018_log.hpp: included at its end (header-only, the default),
//! or compiled once with ENDOHAPTICS_SEPARATE_COMPILATION (core/separate_compilation.hpp).
#pragma once

#include "endohaptics/files/umn_mis_2018_log.hpp"

namespace endohaptics::files {
namespace detail::umn_mis_2018 {

ENDOHAPTICS_DECL bool key_value(std::string_view line, std::pair<std::string, std::string>& out) {
  if (line.empty() || line.front() != '%') return false;
  line.remove_prefix(1);
  const auto eq = line.find('=');
  if (eq == std::string_view::npos || eq == 0) return false;
  const std::string_view key = line.substr(0, eq);
  for (const char c : key) {
    const bool word =
        (c >= 'a' && c <= 'z') || (c >= 'A' && c <= 'Z') || (c >= '0' && c <= '9') || c == '_';
    if (!word) return false;  // free text that happens to contain '='
  }
  out = {std::string(key), std::string(log_text::trim(line.substr(eq + 1)))};
  return true;
}
}  // namespace detail::umn_mis_2018
}  // namespace endohaptics::files

namespace endohaptics::files {

ENDOHAPTICS_DECL Log read_umn_mis_2018(const std::string& path, const UmnMis2018Options& options) {
  namespace lt = detail::log_text;
  namespace lr = detail::log_rows;
  constexpr std::string_view fn = "read_umn_mis_2018";
  for (const double v : {options.futek_newton_metres, options.motor_counts_per_rev,
                         options.spindle_counts_per_rev, options.jaw_counts_per_rev}) {
    if (!(std::isfinite(v) && v > 0)) {
      ENDOHAPTICS_THROW(Error(std::string(fn) + ": conversion constants must be finite and > 0"));
    }
  }
  lt::Lines lines(path, fn, options.read.max_bytes);
  LogReport report = lr::start_report(path);
  std::vector<std::pair<std::string, std::string>> metadata;
  std::size_t first = 0;
  for (const lt::Line* head = lines.peek(); head != nullptr; head = lines.peek()) {
    const std::string_view line = head->text;
    if (line.empty() || line.front() != '%') break;
    std::pair<std::string, std::string> kv;
    if (detail::umn_mis_2018::key_value(line, kv)) metadata.push_back(std::move(kv));
    (void)lines.next();
    ++first;
  }
  if (first == 0) {
    ENDOHAPTICS_THROW(Error(std::string(fn) + ": " + path +
                            ": no '%' header lines: not a UMN mis-tool-characterization log"));
  }
  report.header = true;

  lr::Layout layout;
  layout.function = fn;
  layout.labels = {"time",          "spindle encoder",  "spindle torque",   "current",
                   "jaw encoder",   "grip torque",      "reaction command", "motor command",
                   "motor encoder", "trajectory target"};
  const std::size_t columns = layout.labels.size();
  const lr::Rows rows = lr::read_rows(lines, layout, options.read, report);

  Log log;
  log.source = path;
  log.metadata = std::move(metadata);
  log.time = Eigen::Map<const Eigen::VectorXd>(rows.time.data(),
                                               static_cast<Eigen::Index>(rows.time.size()));
  const Eigen::Index n = log.time.size();
  constexpr double two_pi = 2.0 * std::numbers::pi;
  const double motor_rad = two_pi / options.motor_counts_per_rev;
  const double mnm = options.futek_newton_metres * 1000.0;
  log.names = {"current",          "current_command",  "motor_position", "motor_velocity",
               "grip_torque",      "spindle_position", "spindle_torque", "jaw_position",
               "reaction_command", "trajectory_target"};
  log.units = {"A", "1", "rad", "rad/s", "mN m", "rad", "mN m", "rad", "A", "rad"};
  log.data.resize(n, static_cast<Eigen::Index>(log.names.size()));
  log.data.col(0) = lr::column_of(rows, columns, 3);
  log.data.col(1) = lr::column_of(rows, columns, 7);
  log.data.col(2) = lr::column_of(rows, columns, 8) * motor_rad;
  auto velocity = log.data.col(3);  // a view into data
  velocity.setZero();
  for (Eigen::Index k = 1; k < n; ++k) {
    velocity[k] = (log.data(k, 2) - log.data(k - 1, 2)) / (log.time[k] - log.time[k - 1]);
  }
  log.data.col(4) = lr::column_of(rows, columns, 5) * mnm;
  log.data.col(5) = lr::column_of(rows, columns, 1) * (two_pi / options.spindle_counts_per_rev);
  log.data.col(6) = lr::column_of(rows, columns, 2) * mnm;
  log.data.col(7) = lr::column_of(rows, columns, 4) * (two_pi / options.jaw_counts_per_rev);
  log.data.col(8) = lr::column_of(rows, columns, 6);
  log.data.col(9) = lr::column_of(rows, columns, 9) * motor_rad;
  log.report = std::move(report);
  return log;
}

}  // namespace endohaptics::files
