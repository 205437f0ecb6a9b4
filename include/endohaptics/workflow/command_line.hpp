//! @file
//! Strict command-line numbers and checked program output, shared by the programs in examples/:
//! a number parses whole, in decimal, finite and inside its option's stated range, or fails with
//! a message naming the option ("100abc", "0x10", "nan", "inf", "1e999" all fail), and an output
//! stream that could not be written (full disk, short write) is an error, never a silent success.
//! Configuration time: throws endohaptics::Error. Needs only the standard library.
#pragma once

#include <fcntl.h>
#include <unistd.h>

#include <cerrno>
#include <charconv>
#include <cmath>
#include <concepts>
#include <cstddef>
#include <cstdint>
#include <cstdio>
#include <cstring>
#include <sstream>
#include <string>
#include <string_view>
#include <system_error>
#include <type_traits>
#include <utility>
#include <vector>
#include "endohaptics/core/separate_compilation.hpp"

#include "endohaptics/core/error.hpp"

namespace endohaptics::workflow {

//! What a command-line number may be: an integer type other than bool, or a floating-point type.
template <typename T>
concept OptionNumber = (std::integral<T> && !std::same_as<T, bool>) || std::floating_point<T>;

//! "[min, max]": integers in full, floating point in up to 15 significant digits ("100000",
//! "1e-09").
template <OptionNumber T>
[[nodiscard]] std::string describe_range(T min, T max) {
  std::ostringstream out;
  out.precision(15);
  if constexpr (std::integral<T>) {
    out << "[" << +min << ", " << +max << "]";  // + prints a char-sized type as a number
  } else {
    out << "[" << min << ", " << max << "]";
  }
  return out.str();
}

//! Why `text` is not a number of type T in [min, max]: empty when it is one, and then `value`
//! holds it. Accepted: decimal digits with an optional leading '-' (and, for floating point, a
//! fraction and an exponent), nothing before or after. Refused: hexadecimal, NaN, infinities,
//! overflow, blanks, a leading '+', trailing characters, and values outside [min, max].
template <OptionNumber T>
[[nodiscard]] std::string number_problem(std::string_view text, T min, T max, T& value) {
  const std::string range = describe_range(min, max);
  const std::string quoted = "'" + std::string(text) + "'";
  const char* kind = std::integral<T> ? "an integer" : "a number";
  if (text.empty()) return std::string("empty, expected ") + kind + " in " + range;
  const char* first = text.data();
  const char* last = text.data() + text.size();
  T parsed{};
  std::from_chars_result r{};
  if constexpr (std::integral<T>) {
    r = std::from_chars(first, last, parsed, 10);
  } else {
    r = std::from_chars(first, last, parsed, std::chars_format::general);
  }
  if (r.ec == std::errc::result_out_of_range) {
    return quoted + " is out of range: expected " + kind + " in " + range;
  }
  if (r.ec != std::errc{} || r.ptr != last) {
    return quoted + " is not " + kind + " (decimal digits only, nothing else) in " + range;
  }
  if constexpr (std::floating_point<T>) {
    if (!std::isfinite(parsed)) return quoted + " is not a finite number in " + range;
  }
  if (parsed < min || parsed > max) return quoted + " is outside " + range;
  value = parsed;
  return {};
}

//! `text` as a T in [min, max]; throws Error "<option>: <why>" otherwise (see `number_problem`).
template <OptionNumber T>
[[nodiscard]] T parse_number(std::string_view text, std::string_view option, T min, T max) {
  T value{};
  const std::string problem = number_problem(text, min, max, value);
  if (!problem.empty()) endohaptics::detail::fail(std::string(option) + ": " + problem);
  return value;
}

//! A command-line number check in the shape CLI11's `CLI::Validator` takes
//! (`std::string(std::string&)`, the text left unchanged): returns why the text is refused, or
//! empty when it is a T in [min, max] or one of `keywords` (e.g. "max", "auto"). Integers with a
//! leading zero ("010") are refused too: C's readers, CLI11's among them, take them as octal.
template <OptionNumber T>
class NumberCheck {
 public:
  //! Accepts numbers in [min, max] and the words in `keywords`. Precondition: min <= max.
  NumberCheck(T min, T max, std::vector<std::string> keywords = {})
      : min_(min), max_(max), keywords_(std::move(keywords)) {}

  //! Empty when `text` is accepted, else why not.
  std::string operator()(const std::string& text) const {
    for (const std::string& k : keywords_) {
      if (text == k) return {};
    }
    T value{};
    std::string problem = number_problem(text, min_, max_, value);
    if (problem.empty() && std::integral<T>) {
      const std::string_view digits = std::string_view(text).substr(text.front() == '-' ? 1 : 0);
      if (digits.size() > 1 && digits.front() == '0') {
        problem = "'" + text + "' has a leading zero (read as octal by some parsers): write " +
                  std::to_string(value);
      }
    }
    if (!problem.empty() && !keywords_.empty()) problem += " (or " + alternatives() + ")";
    return problem;
  }

  //! For --help: "INT in [0, 99]", "FLOAT in [1, 100000] or max".
  [[nodiscard]] std::string description() const {
    std::string d =
        std::string(std::integral<T> ? "INT" : "FLOAT") + " in " + describe_range(min_, max_);
    if (!keywords_.empty()) d += " or " + alternatives();
    return d;
  }

 private:
  [[nodiscard]] std::string alternatives() const {
    std::string out;
    for (std::size_t i = 0; i < keywords_.size(); ++i) {
      out += (i == 0 ? "" : i + 1 == keywords_.size() ? " or " : ", ") + keywords_[i];
    }
    return out;
  }

  T min_;
  T max_;
  std::vector<std::string> keywords_;
};

//! A network endpoint from the command line.
struct Endpoint {
  std::string host;        //!< name or address (IPv6 without its brackets)
  std::uint16_t port = 0;  //!< UDP port
};

//! Parses "HOST:PORT" (IPv6: "[addr]:port") given to `option`: the port whole and in 1..65535
//! (0 too when `any_port`: any free port). Throws Error naming the option otherwise.
[[nodiscard]] ENDOHAPTICS_DECL Endpoint parse_endpoint(std::string_view text,
                                                       std::string_view option, bool any_port);

namespace detail {

//! ": <the system's message>" for errno value `error`; for 0 (the stream's error flag was set by
//! an earlier write, whose errno is gone) ": an earlier write failed".
ENDOHAPTICS_DECL std::string reason(int error);

}  // namespace detail

//! Flushes `out` and throws Error naming `what` (e.g. "--log /tmp/x.csv", "standard output")
//! and the system's reason when anything written to it was lost (full disk, short write, closed
//! pipe). The stream stays open.
ENDOHAPTICS_DECL void require_written(std::FILE* out, std::string_view what);

//! Closes `out` and throws Error naming `what` when anything written to it was lost, as
//! `require_written`, or when closing failed. `out` is closed either way.
ENDOHAPTICS_DECL void close_written(std::FILE* out, std::string_view what);

//! Opens `path` for writing ("w": created 0644 less the umask, or truncated) without ever
//! blocking: a FIFO that no one reads is refused at once (ENXIO) instead of hanging the program
//! beyond the reach of SIGINT/SIGTERM. Devices such as /dev/null and /dev/full open as before.
//! `what` names the file in messages ("the log 'x.csv'"). Throws Error.
ENDOHAPTICS_DECL std::FILE* open_output(const std::string& path, std::string_view what);

}  // namespace endohaptics::workflow

#if !defined(ENDOHAPTICS_SEPARATE_COMPILATION)
#include "endohaptics/workflow/impl/command_line.ipp"
#endif
