//! @file
//! Error handling shared by every component: `endohaptics::Error`, the base of all
//! configuration-time exceptions (bad model, unreadable file, invalid option), the number format
//! of their messages, and `ENDOHAPTICS_ASSERT` for programmer errors. Real-time code never
//! throws: it returns a status.
#pragma once

#include <array>
#include <charconv>
#include <cmath>
#include <complex>
#include <concepts>
#include <cstdio>
#include <cstdlib>
#include <stdexcept>
#include <string>
#include <string_view>
#include <type_traits>

//! Throws a configuration-time exception, or, in a build without exceptions (-fno-exceptions),
//! prints its message and aborts. Never used on the real-time path.
#if defined(__cpp_exceptions) || defined(__EXCEPTIONS)
#define ENDOHAPTICS_THROW(...) throw __VA_ARGS__
#else
#define ENDOHAPTICS_THROW(...) ::endohaptics::detail::fail_fast(__VA_ARGS__)
#endif

namespace endohaptics {

//! Thrown at configuration time only; the message says what was wrong and where.
class Error : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

namespace detail {
//! Without exceptions a configuration error cannot be recovered from: say why, then abort.
[[noreturn]] inline void fail_fast(const std::exception& e) noexcept {
  std::fprintf(stderr, "endohaptics: fatal configuration error: %s\n", e.what());
  std::abort();
}

//! Throws Error(message) (configuration time; aborts with the message without exceptions).
[[noreturn]] inline void fail(const std::string& message) { ENDOHAPTICS_THROW(Error(message)); }

//! Runs f() and returns its result; an Error it throws is rethrown with `prefix` and ": " in
//! front of its message (e.g. the file or option it concerns). Configuration time only.
template <typename F>
auto with_context(const std::string& prefix, F&& f) -> decltype(f()) {
#if defined(__cpp_exceptions)
  try {
    return f();
  } catch (const Error& e) {
    fail(prefix + ": " + e.what());
  }
#else
  (void)prefix;
  return f();
#endif
}

//! An integer or floating-point type other than bool: what `format_number` accepts.
template <typename T>
concept RealOrInteger = std::is_arithmetic_v<T> && !std::is_same_v<T, bool>;

//! Shortest text that reads back to the same `value` (std::to_chars), for error messages:
//! "0.1", "-1e-05", "inf", "nan", "42" (std::to_string would round floats to 6 decimals).
template <RealOrInteger Scalar>
[[nodiscard]] std::string format_number(Scalar value) {
  std::array<char, 64> buffer{};  // enough for any long double
  const auto result = std::to_chars(buffer.data(), buffer.data() + buffer.size(), value);
  return std::string(buffer.data(), result.ptr);
}

//! A complex number as "1.2 + 0.5i" or "1.2 - 0.5i", each part round-trip as above.
template <std::floating_point Scalar>
[[nodiscard]] std::string format_number(const std::complex<Scalar>& value) {
  return format_number(value.real()) + (value.imag() < Scalar(0) ? " - " : " + ") +
         format_number(std::abs(value.imag())) + "i";
}

//! "owner: " in front of a message, or nothing when `owner` is empty.
[[nodiscard]] inline std::string owner_prefix(std::string_view owner) {
  return owner.empty() ? std::string() : std::string(owner) + ": ";
}

//! Throws Error "<owner>: <what> is not finite (<value>)" when `value` is NaN or +-Inf.
template <std::floating_point Scalar>
void require_finite(Scalar value, std::string_view owner, std::string_view what) {
  if (!std::isfinite(value)) {
    ENDOHAPTICS_THROW(Error(owner_prefix(owner) + std::string(what) + " is not finite (" +
                            format_number(value) + ")"));
  }
}

//! Anything with rows(), cols() and (i, j) access: Eigen matrices, arrays and expressions.
template <typename M>
concept MatrixLike = requires(const M& m) {
  m.rows();
  m.cols();
  m(0, 0);
};

//! Throws Error "<owner>: <what>(i,j) is not finite (<value>)" naming the first NaN or +-Inf
//! entry of `m`, column by column.
template <MatrixLike M>
void require_finite(const M& m, std::string_view owner, std::string_view what) {
  for (decltype(m.cols()) j = 0; j < m.cols(); ++j) {
    for (decltype(m.rows()) i = 0; i < m.rows(); ++i) {
      if (!std::isfinite(m(i, j))) {
        ENDOHAPTICS_THROW(Error(owner_prefix(owner) + std::string(what) + "(" + std::to_string(i) +
                                "," + std::to_string(j) + ") is not finite (" +
                                format_number(m(i, j)) + ")"));
      }
    }
  }
}
}  // namespace detail

}  // namespace endohaptics

#ifndef ENDOHAPTICS_ASSERT
#include <cassert>
//! Programmer-error check (precondition violated by the caller's code, never by data).
//! Define ENDOHAPTICS_ASSERT before including any endohaptics header to override it.
#define ENDOHAPTICS_ASSERT(condition) assert(condition)
#endif
