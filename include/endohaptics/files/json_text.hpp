//! @file
//! Strict, bounded JSON reading shared by the configuration and model files: a size limit on the
//! file (read through core/regular_file.hpp: regular files only), a nesting limit enforced by the
//! parser itself (nlohmann's SAX interface: parsing stops at the first array or object beyond the
//! limit, so no input can exhaust memory or a stack), duplicate keys refused at any level, and
//! messages that echo at most 60 ASCII characters of any value or key. Configuration time:
//! allocates, throws endohaptics::Error.
#pragma once

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <filesystem>
#include <iterator>
#include <nlohmann/json.hpp>
#include <set>
#include <string>
#include <string_view>
#include <utility>
#include <vector>
#include "endohaptics/core/separate_compilation.hpp"

#include "endohaptics/core/error.hpp"
#include "endohaptics/core/regular_file.hpp"

namespace endohaptics::files::detail::json_text {

using nlohmann::json;

//! At most `max` characters of `text`, with "..." when cut, non-ASCII bytes as '?': every value a
//! message echoes.
ENDOHAPTICS_DECL std::string excerpt(std::string_view text, std::size_t max = 60);

//! A JSON value as a short, ASCII-only text for messages (the value's nesting is bounded by
//! parse_strict's depth limit, so dumping it cannot exhaust the stack).
ENDOHAPTICS_DECL std::string show(const json& value);

//! A key name as it appears in messages: quoted, escaped, at most 60 characters.
ENDOHAPTICS_DECL std::string key_name(std::string_view key);

//! nlohmann's message for an input it refused (a parse error, or a number overflow: "number
//! overflow parsing '1e400'") without its prefix, the token it echoes cut to 60 characters.
ENDOHAPTICS_DECL std::string parse_message(const json::exception& e);

//! Limits of `parse_strict`.
struct Limits {
  int max_depth = 64;            //!< nesting of arrays and objects
  std::string_view needed = "";  //!< what the format needs, e.g. "the bridge configuration needs 3"
  bool comments = true;          //!< `//` and `/* */` allowed
};

//! Parses `text` as JSON with nlohmann's parser through its SAX interface, building the value
//! itself: an array or object nested deeper than `limits.max_depth` stops the parser at once (it
//! never descends further, whatever comments, control characters or NULs precede it), and so does
//! a key repeated in one object. Throws Error "<source>: ..." (the parser's message for invalid
//! JSON; "line L, column C: nested deeper than N levels"; "line L, column C: duplicate key
//! 'a.b'", with the dotted path).
ENDOHAPTICS_DECL json parse_strict(std::string_view text, std::string_view source,
                                   const Limits& limits);

//! The whole regular file at `path` (core/regular_file.hpp: a FIFO, device or directory is
//! refused without blocking), refused when it holds more than `max_bytes`. `what` names the file
//! in messages ("model file", "configuration file"); `limit`, when given, says where the limit
//! comes from ("files::bridge_config_max_bytes").
ENDOHAPTICS_DECL std::string read_bounded(const std::filesystem::path& path, std::size_t max_bytes,
                                          std::string_view what, std::string_view limit = "");

}  // namespace endohaptics::files::detail::json_text

#if !defined(ENDOHAPTICS_SEPARATE_COMPILATION)
#include "endohaptics/files/impl/json_text.ipp"
#endif
