//! @file
//! Function bodies of files/log_text.hpp: included at its end (header-only, the default), or
//! compiled once with ENDOHAPTICS_SEPARATE_COMPILATION (core/separate_compilation.hpp).
#pragma once

#include "endohaptics/files/log_text.hpp"

namespace endohaptics::files::detail::log_text {

ENDOHAPTICS_DECL std::string readable(double value) {
  std::ostringstream out;
  out.precision(10);
  out << value;
  return out.str();
}

ENDOHAPTICS_DECL std::string_view trim(std::string_view s) {
  const auto first = s.find_first_not_of(" \t");
  if (first == std::string_view::npos) return {};
  const auto last = s.find_last_not_of(" \t");
  return s.substr(first, last - first + 1);
}

ENDOHAPTICS_DECL Text read_text(const std::string& path, std::string_view function) {
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

ENDOHAPTICS_DECL std::vector<std::string_view> split(std::string_view line, char separator) {
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

ENDOHAPTICS_DECL Number parse_number(std::string_view field, double& value) {
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

ENDOHAPTICS_DECL bool looks_like_header(std::string_view line, char separator) {
  const auto fields = split(line, separator);
  double v = 0;
  return !fields.empty() && parse_number(fields.front(), v) == Number::non_numeric;
}

ENDOHAPTICS_DECL char detect_separator(std::string_view line) {
  if (line.find(';') != std::string_view::npos) return ';';
  if (line.find(',') != std::string_view::npos) return ',';
  return ' ';
}

}  // namespace endohaptics::files::detail::log_text
