//! @file
//! Function bodies of workflow/error_context.hpp: included at its end (header-only, the default),
//! or compiled once with ENDOHAPTICS_SEPARATE_COMPILATION (core/separate_compilation.hpp).
#pragma once

#include "endohaptics/workflow/error_context.hpp"

namespace endohaptics::workflow {
namespace detail {

ENDOHAPTICS_DECL std::string join(const std::vector<std::string>& names) {
  std::string out;
  for (const auto& n : names) out += (out.empty() ? "" : ", ") + n;
  return out;
}

}  // namespace detail

}  // namespace endohaptics::workflow
