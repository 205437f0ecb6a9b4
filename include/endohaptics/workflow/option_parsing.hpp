//! @file
//! The workflow's settings as text, as endohaptics-identify/-replay take them on the command
//! line and model files record them: offset and x0 mode names, --deadzone lists (input units),
//! and the one-line `key=value` form of Preprocessing kept in a model file's provenance notes.
//! Numbers are read locale-independently and whole (workflow/command_line.hpp); settings outside
//! their ranges (workflow/preprocessing.hpp, limits) are refused. Configuration time: throws
//! endohaptics::Error.
#pragma once

#include <Eigen/Core>
#include <algorithm>
#include <cstddef>
#include <optional>
#include <sstream>
#include <string>
#include <string_view>
#include <vector>
#include "endohaptics/core/separate_compilation.hpp"

#include "endohaptics/core/error.hpp"
#include "endohaptics/files/log_text.hpp"
#include "endohaptics/files/model_file.hpp"
#include "endohaptics/workflow/command_line.hpp"
#include "endohaptics/workflow/error_context.hpp"
#include "endohaptics/workflow/model_comparison.hpp"
#include "endohaptics/workflow/preprocessing.hpp"
#include "endohaptics/workflow/workflow_options.hpp"

namespace endohaptics::workflow {

namespace detail {

//! Whole-string number; throws naming `what` and the text otherwise.
ENDOHAPTICS_DECL double parse_double(std::string_view text, const std::string& what);

ENDOHAPTICS_DECL std::vector<std::string_view> split(std::string_view text, char separator);

}  // namespace detail

//! Mode named `name` (as `to_string` writes it). Throws Error naming the value otherwise.
[[nodiscard]] ENDOHAPTICS_DECL OffsetMode offset_mode_from_string(std::string_view name);

//! One line, `key=value` pairs separated by blanks; `parse_preprocessing` reads it back.
[[nodiscard]] ENDOHAPTICS_DECL std::string describe(const Preprocessing& p);

//! Reads what `describe` wrote. Unknown keys, bad values and values outside their ranges
//! (`validate`) throw Error naming them.
[[nodiscard]] ENDOHAPTICS_DECL Preprocessing parse_preprocessing(std::string_view text);

//! The preprocessing a model file records in its provenance notes (a line starting with
//! "preprocessing: "), if any. Throws Error when the line is there but malformed.
[[nodiscard]] ENDOHAPTICS_DECL std::optional<Preprocessing> recorded_preprocessing(
    const files::ModelFile& m);

//! Parses "steady", "zero", "stored" or "oracle". "estimate" (the old name of oracle) is refused
//! with a message: its numbers used the measured output and are not force-estimation results.
//! Throws Error otherwise.
[[nodiscard]] ENDOHAPTICS_DECL InitialStateMode initial_state_from_string(std::string_view name);

//! Parses --deadzone: "auto", "none" or a half width for every input, or a comma-separated list
//! with one of those per input. Throws Error naming the value or the count.
[[nodiscard]] ENDOHAPTICS_DECL std::vector<DeadzoneSetting> parse_deadzone(std::string_view text,
                                                                           std::size_t inputs);

}  // namespace endohaptics::workflow

#if !defined(ENDOHAPTICS_SEPARATE_COMPILATION)
#include "endohaptics/workflow/impl/option_parsing.ipp"
#endif
