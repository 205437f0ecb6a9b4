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
#include "endohaptics/core/separate_compilation.hpp"

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
[[nodiscard]] ENDOHAPTICS_DECL LogFormat parse_log_format(std::string_view name);

//! Reads `path` in `format` with the shared policies `read`.
[[nodiscard]] ENDOHAPTICS_DECL Log read_log(const std::string& path, LogFormat format,
                                            const LogReadOptions& read = {});

}  // namespace endohaptics::files

#if !defined(ENDOHAPTICS_SEPARATE_COMPILATION)
#include "endohaptics/files/impl/log_reader.ipp"
#endif
