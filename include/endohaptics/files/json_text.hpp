//! @file
//! Strict, bounded JSON reading shared by the configuration and model files: a size limit on the
//! file, a nesting limit checked before the parser sees the text (no input can exhaust a stack),
//! duplicate keys refused at any level, and messages that echo at most 60 ASCII characters of any
//! value or key. Configuration time: allocates, throws endohaptics::Error.
#pragma once

#include <cmath>
#include <cstddef>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <set>
#include <string>
#include <string_view>
#include <utility>
#include <vector>
#include "endohaptics/core/separate_compilation.hpp"

#include "endohaptics/core/error.hpp"

namespace endohaptics::files::detail::json_text {

using nlohmann::json;

//! At most `max` characters of `text`, with "..." when cut, non-ASCII bytes as '?': every value a
//! message echoes.
ENDOHAPTICS_DECL std::string excerpt(std::string_view text, std::size_t max = 60);

//! A JSON value as a short, ASCII-only text for messages (the value's nesting is bounded by the
//! depth check that preceded parsing, so dumping it cannot exhaust the stack).
ENDOHAPTICS_DECL std::string show(const json& value);

//! A key name as it appears in messages: quoted, escaped, at most 60 characters.
ENDOHAPTICS_DECL std::string key_name(std::string_view key);

//! Refuses nesting deeper than `max_depth` before the parser sees the text: a quick scan counting
//! brackets outside strings and comments. `needed`: what the format itself needs, for the message.
ENDOHAPTICS_DECL void check_depth(std::string_view text, std::string_view source, int max_depth,
                                  std::string_view needed);

//! nlohmann's message for an input it refused (a parse error, or a number overflow: "number
//! overflow parsing '1e400'") without its prefix, the token it echoes cut to 60 characters.
ENDOHAPTICS_DECL std::string parse_message(const json::exception& e);

//! Limits of `parse_strict` and `read_bounded`.
struct Limits {
  int max_depth = 64;            //!< nesting of arrays and objects
  std::string_view needed = "";  //!< what the format needs, e.g. "the bridge configuration needs 3"
  bool comments = true;          //!< `//` and `/* */` allowed
};

//! Parses `text` as JSON after the depth check; refuses duplicate keys anywhere. Throws Error
//! "<source>: ..." (the parser's message for invalid JSON, the dotted path of a duplicate key).
ENDOHAPTICS_DECL json parse_strict(std::string_view text, std::string_view source,
                                   const Limits& limits);

//! The whole file at `path`, refused when longer than `max_bytes` (read at most max_bytes + 1)
//! or unreadable. `what` names the file in messages ("model file", "configuration file").
ENDOHAPTICS_DECL std::string read_bounded(const std::filesystem::path& path, std::size_t max_bytes,
                                          std::string_view what);

}  // namespace endohaptics::files::detail::json_text

#if !defined(ENDOHAPTICS_SEPARATE_COMPILATION)
#include "endohaptics/files/impl/json_text.ipp"
#endif
