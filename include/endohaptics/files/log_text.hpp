//! @file
//! The text layer of the log readers (internals, namespace detail::log_text): a file read into
//! lines (UTF-8 byte order mark and the CR of CR LF removed, blank lines counted), fields split
//! at ',', ';', tab or runs of blanks, and locale-independent whole-field numbers
//! (std::from_chars). Configuration time: allocates, throws endohaptics::Error naming the file.
#pragma once

#include <algorithm>
#include <charconv>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <sstream>
#include <string>
#include <string_view>
#include <system_error>
#include <vector>
#include "endohaptics/core/separate_compilation.hpp"

#include "endohaptics/core/error.hpp"

namespace endohaptics::files::detail::log_text {

//! Ten significant digits: enough for the logs' time stamps, short enough to read.
ENDOHAPTICS_DECL std::string readable(double value);

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

ENDOHAPTICS_DECL std::string_view trim(std::string_view s);

ENDOHAPTICS_DECL Text read_text(const std::string& path, std::string_view function);

//! Fields of a line: split at `separator` (' ' = runs of blanks and tabs), each trimmed.
ENDOHAPTICS_DECL std::vector<std::string_view> split(std::string_view line, char separator);

enum class Number : std::uint8_t { ok, empty, non_numeric, non_finite };

//! Locale-independent parse of a whole field as a double.
ENDOHAPTICS_DECL Number parse_number(std::string_view field, double& value);

ENDOHAPTICS_DECL bool looks_like_header(std::string_view line, char separator);

//! Detects the separator of a line: ';' if present, else ',' if present, else blanks.
ENDOHAPTICS_DECL char detect_separator(std::string_view line);

}  // namespace endohaptics::files::detail::log_text

#if !defined(ENDOHAPTICS_SEPARATE_COMPILATION)
#include "endohaptics/files/impl/log_text.ipp"
#endif
