//! @file
//! Function bodies of workflow/command_line.hpp: included at its end (header-only, the default), or
//! compiled once with ENDOHAPTICS_SEPARATE_COMPILATION (core/separate_compilation.hpp).
#pragma once

#include "endohaptics/workflow/command_line.hpp"

namespace endohaptics::workflow {
namespace detail {

ENDOHAPTICS_DECL std::string reason(int error) {
  return error != 0 ? std::string(": ") + std::strerror(error) : ": an earlier write failed";
}
}  // namespace detail
}  // namespace endohaptics::workflow

namespace endohaptics::workflow {

ENDOHAPTICS_DECL void require_written(std::FILE* out, std::string_view what) {
  errno = 0;
  const bool failed = std::fflush(out) != 0 || std::ferror(out) != 0;
  if (failed) {
    const int error = errno;
    endohaptics::detail::fail("writing " + std::string(what) + " failed" + detail::reason(error));
  }
}

ENDOHAPTICS_DECL std::FILE* open_output(const std::string& path, std::string_view what) {
  int fd = -1;
  do {
    fd = ::open(path.c_str(), O_WRONLY | O_CREAT | O_TRUNC | O_NONBLOCK | O_CLOEXEC, 0644);
  } while (fd < 0 && errno == EINTR);
  if (fd < 0) {
    const int error = errno;
    endohaptics::detail::fail(
        "cannot write " + std::string(what) +
        (error == ENXIO ? ": it is a FIFO (named pipe) that no process reads" : "") +
        detail::reason(error));
  }
  // Writes block as usual from here on (a full pipe waits for its reader).
  if (const int flags = ::fcntl(fd, F_GETFL); flags >= 0) {
    (void)::fcntl(fd, F_SETFL, flags & ~O_NONBLOCK);
  }
  std::FILE* out = ::fdopen(fd, "w");
  if (out == nullptr) {
    const int error = errno;
    ::close(fd);
    endohaptics::detail::fail("cannot write " + std::string(what) + detail::reason(error));
  }
  return out;
}

ENDOHAPTICS_DECL void close_written(std::FILE* out, std::string_view what) {
  errno = 0;
  const bool failed = std::fflush(out) != 0 || std::ferror(out) != 0;
  const int error = errno;
  const bool close_failed = std::fclose(out) != 0;
  if (failed || close_failed) {
    const int error_number = error != 0 ? error : errno;
    endohaptics::detail::fail("writing " + std::string(what) + " failed" +
                              detail::reason(error_number));
  }
}

ENDOHAPTICS_DECL Endpoint parse_endpoint(std::string_view text, std::string_view option,
                                         bool any_port) {
  const auto colon = text.rfind(':');
  if (colon == std::string_view::npos || colon == 0 || colon + 1 == text.size()) {
    ENDOHAPTICS_THROW(
        Error(std::string(option) + " must be HOST:PORT, got '" + std::string(text) + "'"));
  }
  std::string host(text.substr(0, colon));
  if (host.size() >= 2 && host.front() == '[' && host.back() == ']') {
    host = host.substr(1, host.size() - 2);
  }
  const auto port = parse_number<std::uint16_t>(
      text.substr(colon + 1), std::string(option) + " port", any_port ? 0 : 1, 65535);
  return {std::move(host), port};
}

}  // namespace endohaptics::workflow
