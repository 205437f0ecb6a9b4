//! @file
//! Internals shared by the workflow headers (namespace detail): endohaptics::Error messages that
//! name the file, option or method they concern (fail, with_context), and the numbers and name
//! lists written into them. Configuration time: throws endohaptics::Error.
#pragma once

#include <string>
#include <vector>

#include "endohaptics/core/error.hpp"

namespace endohaptics::workflow {

namespace detail {

[[noreturn]] inline void fail(const std::string& message) { ENDOHAPTICS_THROW(Error(message)); }

using endohaptics::detail::format_number;

inline std::string join(const std::vector<std::string>& names) {
  std::string out;
  for (const auto& n : names) out += (out.empty() ? "" : ", ") + n;
  return out;
}

//! Rethrows an Error with `prefix` in front of its message.
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

}  // namespace detail

}  // namespace endohaptics::workflow
