//! @file
//! Key files for protocol v2: exactly 32 random bytes (libsodium randombytes_buf), no text, mode
//! 0600. generate_key_file refuses to overwrite; load_key_file refuses a file that group or
//! others may read, or of any other length. Configuration time: throws Error naming the file and
//! the reason, never the key. POSIX. See docs/protocol.md, "Key file".
#pragma once

#include <fcntl.h>
#include <sodium.h>
#include <sys/stat.h>
#include <unistd.h>

#include <array>
#include <cerrno>
#include <cstddef>
#include <cstdio>
#include <cstring>
#include <string>
#include <utility>

#include "endohaptics/core/error.hpp"
#include "endohaptics/protocol/secure_codec.hpp"

namespace endohaptics::protocol {

namespace detail {

//! Closes a file descriptor on scope exit.
struct FdGuard {
  int fd = -1;  //!< the descriptor, -1: none
  ~FdGuard() {
    if (fd >= 0) ::close(fd);
  }
};

//! "key file 'path': what: strerror(errno)".
inline std::string key_file_error(const std::string& path, const std::string& what, int err = 0) {
  std::string m = "key file '" + path + "': " + what;
  if (err != 0) m += ": " + std::string(std::strerror(err));
  return m;
}

}  // namespace detail

//! Writes a new key file at `path`: 32 bytes from libsodium's random source, mode 0600, created
//! exclusively (an existing file, or a symbolic link, is refused). Throws Error.
inline void generate_key_file(const std::string& path) {
  if (sodium_init() < 0) ENDOHAPTICS_THROW(Error("libsodium failed to initialise"));
  detail::FdGuard f{::open(path.c_str(), O_WRONLY | O_CREAT | O_EXCL | O_NOFOLLOW | O_CLOEXEC,
                           S_IRUSR | S_IWUSR)};
  if (f.fd < 0) {
    const int err = errno;
    ENDOHAPTICS_THROW(Error(detail::key_file_error(
        path, err == EEXIST ? "exists already; refusing to overwrite a key" : "cannot create",
        err == EEXIST ? 0 : err)));
  }
  // The umask may only have removed bits; make the mode exactly 0600 regardless.
  if (::fchmod(f.fd, S_IRUSR | S_IWUSR) != 0) {
    const int err = errno;
    ::unlink(path.c_str());
    ENDOHAPTICS_THROW(Error(detail::key_file_error(path, "cannot set mode 0600", err)));
  }
  std::array<unsigned char, SecureKey::size> key{};
  randombytes_buf(key.data(), key.size());
  std::size_t written = 0;
  while (written < key.size()) {
    const ssize_t n = ::write(f.fd, key.data() + written, key.size() - written);
    if (n < 0 && errno == EINTR) continue;
    if (n <= 0) {
      const int err = n < 0 ? errno : EIO;
      sodium_memzero(key.data(), key.size());
      ::unlink(path.c_str());
      ENDOHAPTICS_THROW(Error(detail::key_file_error(path, "cannot write", err)));
    }
    written += static_cast<std::size_t>(n);
  }
  sodium_memzero(key.data(), key.size());
  if (::fsync(f.fd) != 0 || ::close(std::exchange(f.fd, -1)) != 0) {
    const int err = errno;
    ::unlink(path.c_str());
    ENDOHAPTICS_THROW(Error(detail::key_file_error(path, "cannot write", err)));
  }
}

//! Reads the key file at `path`: a regular file of exactly 32 bytes that neither group nor others
//! may read or write (chmod 600). Throws Error naming the file and the reason.
inline SecureKey load_key_file(const std::string& path) {
  detail::FdGuard f{::open(path.c_str(), O_RDONLY | O_CLOEXEC | O_NOFOLLOW)};
  if (f.fd < 0) ENDOHAPTICS_THROW(Error(detail::key_file_error(path, "cannot open", errno)));
  struct stat st {};
  if (::fstat(f.fd, &st) != 0) {
    ENDOHAPTICS_THROW(Error(detail::key_file_error(path, "cannot stat", errno)));
  }
  if (!S_ISREG(st.st_mode)) ENDOHAPTICS_THROW(Error(detail::key_file_error(path, "not a file")));
  if ((st.st_mode & (S_IRWXG | S_IRWXO)) != 0) {
    char mode[8];
    std::snprintf(mode, sizeof(mode), "%04o", static_cast<unsigned>(st.st_mode & 07777));
    ENDOHAPTICS_THROW(Error(detail::key_file_error(
        path, std::string("mode ") + mode +
                  " lets group or others read or write the key; run: chmod 600 " + path)));
  }
  if (st.st_size != static_cast<off_t>(SecureKey::size)) {
    ENDOHAPTICS_THROW(Error(detail::key_file_error(
        path, "must hold exactly " + std::to_string(SecureKey::size) + " bytes, holds " +
                  std::to_string(st.st_size) + " (make one with --generate-key FILE)")));
  }
  std::array<std::byte, SecureKey::size> key{};
  std::size_t got = 0;
  while (got < key.size()) {
    const ssize_t n = ::read(f.fd, key.data() + got, key.size() - got);
    if (n < 0 && errno == EINTR) continue;
    if (n <= 0) {
      sodium_memzero(key.data(), key.size());
      ENDOHAPTICS_THROW(
          Error(detail::key_file_error(path, "cannot read 32 bytes", n < 0 ? errno : 0)));
    }
    got += static_cast<std::size_t>(n);
  }
  SecureKey result{std::span<const std::byte, SecureKey::size>(key)};
  sodium_memzero(key.data(), key.size());
  return result;
}

}  // namespace endohaptics::protocol
