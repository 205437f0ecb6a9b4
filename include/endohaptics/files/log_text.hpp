//! @file
//! The text layer of the log readers (internals, namespace detail::log_text): a file read line by
//! line through core/regular_file.hpp (a regular file of at most a stated size; never the whole
//! file at once), UTF-8 byte order mark and the CR of CR LF removed, blank lines counted; fields
//! split at ',', ';', tab or runs of blanks, and locale-independent whole-field numbers
//! (std::from_chars). Configuration time: allocates, throws endohaptics::Error naming the file.
#pragma once

#include <algorithm>
#include <charconv>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <cstring>
#include <deque>
#include <sstream>
#include <string>
#include <string_view>
#include <system_error>
#include <vector>
#include "endohaptics/core/separate_compilation.hpp"

#include "endohaptics/core/error.hpp"
#include "endohaptics/core/regular_file.hpp"

namespace endohaptics::files {

//! Largest log file the readers read by default, bytes (LogReadOptions::max_bytes,
//! TickLogOptions::max_bytes): 1 GiB, about 750 times the largest log of ../shared/data (1.4 MB)
//! and about 50 minutes of the bridge's tick log at 1 kHz. Larger files are refused with a
//! message naming the file, its size and the option that raises the limit.
inline constexpr std::uint64_t default_log_max_bytes = std::uint64_t{1} << 30;

}  // namespace endohaptics::files

namespace endohaptics::files::detail::log_text {

//! Ten significant digits: enough for the logs' time stamps, short enough to read.
ENDOHAPTICS_DECL std::string readable(double value);

//! A file's raw lines, read through one descriptor in blocks (core/regular_file.hpp: a regular
//! file of at most `max_bytes`), one line held at a time: what std::getline gives, without the
//! file held in memory.
class LineReader {
 public:
  //! Opens `path`; `what` names it in messages ("read_csv: log file"), `raise` says how to raise
  //! the limit ("raise LogReadOptions::max_bytes to read it").
  ENDOHAPTICS_DECL LineReader(const std::string& path, std::string_view what,
                              std::uint64_t max_bytes, std::string_view raise);
  //! The next line without its '\n' into `line`; `terminated`: it ended with '\n' (false for a
  //! last line without one). False at the end of the file.
  ENDOHAPTICS_DECL bool next(std::string& line, bool& terminated);
  //! As next(), for callers that need not know whether the line was terminated.
  bool next(std::string& line) {
    bool terminated = false;
    return next(line, terminated);
  }
  //! The open file.
  [[nodiscard]] const RegularFile& file() const noexcept { return file_; }

 private:
  RegularFile file_;
  std::vector<char> buffer_;
  std::size_t begin_ = 0;  // unread bytes: [begin_, end_)
  std::size_t end_ = 0;
  bool at_end_ = false;
};

//! One non-blank line of a log.
struct Line {
  std::size_t number = 0;  //!< 1-based, counting every line of the file
  std::string text;        //!< without '\n' and the CR of CR LF
};

//! The non-blank lines of a log file, one at a time (LineReader), with the counts a LogReport
//! shows; any number of lines may be looked at ahead (peek) before they are taken (next).
class Lines {
 public:
  //! Opens `path` for `function` ("read_csv"), at most `max_bytes`: "<function>: log file
  //! '<path>' ...", with "raise LogReadOptions::max_bytes" when it is too large.
  ENDOHAPTICS_DECL Lines(const std::string& path, std::string_view function,
                         std::uint64_t max_bytes);
  //! The `ahead`-th line not yet taken (0: the next one), or null past the last; valid until
  //! next() takes it.
  ENDOHAPTICS_DECL const Line* peek(std::size_t ahead = 0);
  //! Takes the next line, or null at the end; valid until the next call.
  ENDOHAPTICS_DECL const Line* next();

  //! Lines read so far, blank ones and the last line without '\n' included.
  [[nodiscard]] std::size_t total_lines() const noexcept { return total_lines_; }
  //! Lines read so far that ended with CR LF.
  [[nodiscard]] std::size_t crlf_lines() const noexcept { return crlf_lines_; }
  //! Blank lines read so far (nothing but blanks and tabs).
  [[nodiscard]] std::size_t blank_lines() const noexcept { return blank_lines_; }
  //! True when the file starts with a UTF-8 byte order mark.
  [[nodiscard]] bool byte_order_mark() const noexcept { return byte_order_mark_; }
  //! The file's path.
  [[nodiscard]] const std::string& path() const noexcept { return reader_.file().path(); }

 private:
  // Reads the next non-blank line into `out`; false at the end.
  ENDOHAPTICS_DECL bool read(Line& out);

  LineReader reader_;
  std::deque<Line> ahead_;
  Line current_;
  std::string raw_;
  std::size_t total_lines_ = 0;
  std::size_t crlf_lines_ = 0;
  std::size_t blank_lines_ = 0;
  bool byte_order_mark_ = false;
  bool first_ = true;
};

ENDOHAPTICS_DECL std::string_view trim(std::string_view s);

//! Fields of a line: split at `separator` (' ' = runs of blanks and tabs), each trimmed.
ENDOHAPTICS_DECL std::vector<std::string_view> split(std::string_view line, char separator);

enum class Number : std::uint8_t { ok, empty, non_numeric, non_finite };

//! Locale-independent parse of a whole field as a double.
ENDOHAPTICS_DECL Number parse_number(std::string_view field, double& value);

ENDOHAPTICS_DECL bool looks_like_header(std::string_view line, char separator);

//! Detects the separator of a line: ';' if present, else ',' if present, else blanks.
ENDOHAPTICS_DECL char detect_separator(std::string_view line);

}  // namespace endohaptics::files::detail::log_text

#if !defined(ENDOHAPTICS_SEPARATE_COMPILATION)
#include "endohaptics/files/impl/log_text.ipp"
#endif
