//! @file
//! Readers for measurement logs used in system identification, and the format by name for
//! command lines: the 2016 EndoWrist logs (files/endowrist_2016_log.hpp) and generic headed CSV
//! (files/csv_log.hpp), both returning a Log (files/log.hpp) whose LogReport
//! (files/log_report.hpp) counts every dropped or repaired line, under the policies of
//! LogReadOptions (files/log_rows.hpp). Configuration time: throws endohaptics::Error.
#pragma once

#include <cstdint>
#include <string>
#include <string_view>

#include "endohaptics/core/error.hpp"
#include "endohaptics/files/csv_log.hpp"
#include "endohaptics/files/endowrist_2016_log.hpp"
#include "endohaptics/files/log.hpp"
#include "endohaptics/files/log_rows.hpp"
#include "endohaptics/files/umn_mis_2018_log.hpp"

namespace endohaptics::files {

//! The log formats a command line can name.
enum class LogFormat : std::uint8_t {
  endowrist_2016,  //!< "endowrist-2016": read_endowrist_2016 with default options
  csv,             //!< "csv": read_csv with default options
  umn_mis_2018,    //!< "umn-mis-2018": read_umn_mis_2018 with default options
};

//! Parses "endowrist-2016", "csv" or "umn-mis-2018". Throws Error naming the value and the
//! valid ones.
[[nodiscard]] inline LogFormat parse_log_format(std::string_view name) {
  if (name == "endowrist-2016") return LogFormat::endowrist_2016;
  if (name == "csv") return LogFormat::csv;
  if (name == "umn-mis-2018") return LogFormat::umn_mis_2018;
  ENDOHAPTICS_THROW(Error("unknown log format '" + std::string(name) +
                          "' (valid: endowrist-2016, csv, umn-mis-2018)"));
}

//! Reads `path` in `format` with the shared policies `read`.
[[nodiscard]] inline Log read_log(const std::string& path, LogFormat format,
                                  const LogReadOptions& read = {}) {
  if (format == LogFormat::endowrist_2016) {
    Endowrist2016Options o;
    o.read = read;
    return read_endowrist_2016(path, o);
  }
  if (format == LogFormat::umn_mis_2018) {
    UmnMis2018Options o;
    o.read = read;
    return read_umn_mis_2018(path, o);
  }
  CsvOptions o;
  o.read = read;
  return read_csv(path, o);
}

}  // namespace endohaptics::files
