//! @file
//! Internals shared by the workflow headers (namespace detail): endohaptics::Error messages that
//! name the file, option or method they concern (fail, with_context), and the numbers and name
//! lists written into them. Configuration time: throws endohaptics::Error.
#pragma once

#include <string>
#include <vector>
#include "endohaptics/core/separate_compilation.hpp"

#include "endohaptics/core/error.hpp"

namespace endohaptics::workflow {

namespace detail {

using endohaptics::detail::fail;

using endohaptics::detail::format_number;

ENDOHAPTICS_DECL std::string join(const std::vector<std::string>& names);

using endohaptics::detail::with_context;

}  // namespace detail

}  // namespace endohaptics::workflow

#if !defined(ENDOHAPTICS_SEPARATE_COMPILATION)
#include "endohaptics/workflow/impl/error_context.ipp"
#endif
