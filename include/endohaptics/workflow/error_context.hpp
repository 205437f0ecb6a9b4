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

using endohaptics::detail::fail;

using endohaptics::detail::format_number;

inline std::string join(const std::vector<std::string>& names) {
  std::string out;
  for (const auto& n : names) out += (out.empty() ? "" : ", ") + n;
  return out;
}

using endohaptics::detail::with_context;

}  // namespace detail

}  // namespace endohaptics::workflow
