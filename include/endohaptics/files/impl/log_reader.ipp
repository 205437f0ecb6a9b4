//! @file
//! Function bodies of files/log_reader.hpp: included at its end (header-only, the default), or
//! compiled once with ENDOHAPTICS_SEPARATE_COMPILATION (core/separate_compilation.hpp).
#pragma once

#include "endohaptics/files/log_reader.hpp"

namespace endohaptics::files {

ENDOHAPTICS_DECL LogFormat parse_log_format(std::string_view name) {
  if (name == "endowrist-2016") return LogFormat::endowrist_2016;
  if (name == "csv") return LogFormat::csv;
  if (name == "umn-mis-2018") return LogFormat::umn_mis_2018;
  ENDOHAPTICS_THROW(Error("unknown log format '" + std::string(name) +
                          "' (valid: endowrist-2016, csv, umn-mis-2018)"));
}

ENDOHAPTICS_DECL Log read_log(const std::string& path, LogFormat format,
                              const LogReadOptions& read) {
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
