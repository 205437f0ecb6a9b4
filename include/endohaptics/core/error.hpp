//! @file
//! Error handling shared by every component: `endohaptics::Error`, the base of all
//! configuration-time exceptions (bad model, unreadable file, invalid option), and
//! `ENDOHAPTICS_ASSERT` for programmer errors. Real-time code never throws: it returns a status.
#pragma once

#include <cstdio>
#include <cstdlib>
#include <stdexcept>
#include <string>

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
}  // namespace detail

}  // namespace endohaptics

//! Throws a configuration-time exception, or, in a build without exceptions (-fno-exceptions),
//! prints its message and aborts. Never used on the real-time path.
#if defined(__cpp_exceptions) || defined(__EXCEPTIONS)
#define ENDOHAPTICS_THROW(...) throw __VA_ARGS__
#else
#define ENDOHAPTICS_THROW(...) ::endohaptics::detail::fail_fast(__VA_ARGS__)
#endif

#ifndef ENDOHAPTICS_ASSERT
#include <cassert>
//! Programmer-error check (precondition violated by the caller's code, never by data).
//! Define ENDOHAPTICS_ASSERT before including any endohaptics header to override it.
#define ENDOHAPTICS_ASSERT(condition) assert(condition)
#endif
