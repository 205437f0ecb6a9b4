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

#include "endohaptics/core/error.hpp"

namespace endohaptics::files::detail::log_text {

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

}  // namespace endohaptics::files::detail::log_text
