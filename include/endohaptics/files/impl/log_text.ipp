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

ENDOHAPTICS_DECL LineReader::LineReader(const std::string& path, std::string_view what,
                                        std::uint64_t max_bytes, std::string_view raise)
    : file_(path, what) {
  file_.limit(max_bytes, raise);
  buffer_.resize(std::size_t{1} << 16);
}

ENDOHAPTICS_DECL bool LineReader::next(std::string& line, bool& terminated) {
  line.clear();
  for (;;) {
    if (begin_ < end_) {
      const char* first = buffer_.data() + begin_;
      const auto* newline = static_cast<const char*>(std::memchr(first, '\n', end_ - begin_));
      if (newline != nullptr) {
        line.append(first, newline);
        begin_ += static_cast<std::size_t>(newline - first) + 1;
        terminated = true;
        return true;
      }
      line.append(first, end_ - begin_);
      begin_ = end_ = 0;
    }
    if (at_end_) break;
    end_ = file_.read(buffer_.data(), buffer_.size());
    begin_ = 0;
    at_end_ = end_ == 0;
  }
  terminated = false;
  return !line.empty();  // a last line without '\n'; nothing: the end
}

ENDOHAPTICS_DECL Lines::Lines(const std::string& path, std::string_view function,
                              std::uint64_t max_bytes)
    : reader_(path, std::string(function) + ": log file", max_bytes,
              "raise LogReadOptions::max_bytes to read it") {}

ENDOHAPTICS_DECL bool Lines::read(Line& out) {
  bool terminated = false;
  while (reader_.next(raw_, terminated)) {
    std::string_view line = raw_;
    if (first_) {
      first_ = false;
      if (line.starts_with("\xEF\xBB\xBF")) {
        byte_order_mark_ = true;
        line.remove_prefix(3);
        if (line.empty() && !terminated) break;  // the mark alone: no line
      }
    }
    ++total_lines_;
    if (terminated && !line.empty() && line.back() == '\r') {
      ++crlf_lines_;
      line.remove_suffix(1);
    }
    if (trim(line).empty()) {
      ++blank_lines_;
      continue;
    }
    out.number = total_lines_;
    out.text.assign(line);
    return true;
  }
  return false;
}

ENDOHAPTICS_DECL const Line* Lines::peek(std::size_t ahead) {
  while (ahead_.size() <= ahead) {
    Line line;
    if (!read(line)) return nullptr;
    ahead_.push_back(std::move(line));
  }
  return &ahead_[ahead];
}

ENDOHAPTICS_DECL const Line* Lines::next() {
  if (!ahead_.empty()) {
    current_ = std::move(ahead_.front());
    ahead_.pop_front();
    return &current_;
  }
  return read(current_) ? &current_ : nullptr;
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
