//! @file
//! Key files for protocol v2: exactly 32 random bytes (libsodium randombytes_buf), no text, mode
//! 0600. generate_key_file refuses to overwrite; load_key_file refuses a file that group or
//! others may read, or of any other length, and anything but a regular file (a FIFO or device is
//! refused without blocking: core/regular_file.hpp). Configuration time: throws Error naming the
//! file and the reason, never the key. POSIX. See docs/protocol.md, "Key file".
#pragma once

#include <fcntl.h>
#include <sodium.h>
#include <sys/stat.h>
#include <unistd.h>

#include <array>
#include <cerrno>
#include <cstddef>
#include <cstdint>
#include <cstdio>
#include <cstring>
#include <span>
#include <string>
#include <utility>
#include <vector>

#include "endohaptics/core/error.hpp"
#include "endohaptics/core/regular_file.hpp"
#include "endohaptics/protocol/key_ring.hpp"
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

//! Throws: the key file holds `length` bytes, not 32.
[[noreturn]] inline void refuse_key_length(const std::string& path, std::uint64_t length) {
  ENDOHAPTICS_THROW(Error(key_file_error(
      path, "must hold exactly " + std::to_string(SecureKey::size) + " bytes, holds " +
                std::to_string(length) + " (make one with --generate-key FILE)")));
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

//! Refuses the mode of key file `path` (st_mode) when group or others may read or write it.
//! Throws Error naming the file, the mode and the fix (chmod 600).
inline void check_key_file_mode(mode_t mode, const std::string& path) {
  if ((mode & (S_IRWXG | S_IRWXO)) != 0) {
    char text[8];
    std::snprintf(text, sizeof(text), "%04o", static_cast<unsigned>(mode & 07777));
    ENDOHAPTICS_THROW(Error(detail::key_file_error(
        path, std::string("mode ") + text +
                  " lets group or others read or write the key; run: chmod 600 " + path)));
  }
}

//! Refuses key file `path` owned by `owner` when the running user (`user`, the effective uid) is
//! someone else: a key another account owns may be replaced by that account (a root bridge loading
//! a key `nobody` owns). Throws Error naming the file, both users and the fix.
inline void check_key_file_owner(uid_t owner, uid_t user, const std::string& path) {
  if (owner != user) {
    ENDOHAPTICS_THROW(Error(detail::key_file_error(
        path, "is owned by uid " + std::to_string(owner) + ", not by the user running this (uid " +
                  std::to_string(user) + "): another account could replace the key; run: chown " +
                  std::to_string(user) + " " + path)));
  }
}

//! Refuses key file `path` whose directory others may write to (group- or world-writable,
//! sticky or not): anyone who can write there can swap the file between two runs. Throws Error
//! naming the directory and the fix.
inline void check_key_directory(const std::string& path) {
  const auto slash = path.rfind('/');
  const std::string dir = slash == std::string::npos ? "."
                          : slash == 0               ? "/"
                                                     : path.substr(0, slash);
  struct stat st {};
  if (::stat(dir.c_str(), &st) != 0) {
    ENDOHAPTICS_THROW(Error(
        detail::key_file_error(path, "its directory '" + dir + "' cannot be examined", errno)));
  }
  if ((st.st_mode & (S_IWGRP | S_IWOTH)) != 0) {
    char text[8];
    std::snprintf(text, sizeof(text), "%04o", static_cast<unsigned>(st.st_mode & 07777));
    ENDOHAPTICS_THROW(Error(detail::key_file_error(
        path, "its directory '" + dir + "' (mode " + text +
                  ") lets group or others write there, so the key could be swapped; keep keys in "
                  "a directory only you can write (e.g. chmod 700 " +
                  dir + ")")));
  }
}

//! The key held by `bytes`, the content of key file `path`: exactly 32 bytes. Throws Error naming
//! the file and the length, never the bytes.
inline SecureKey key_from_bytes(std::span<const std::byte> bytes, const std::string& path) {
  if (bytes.size() != SecureKey::size) detail::refuse_key_length(path, bytes.size());
  return SecureKey{bytes.first<SecureKey::size>()};
}

//! Reads the key file at `path`: a regular file (not a symbolic link, FIFO or device) of exactly
//! 32 bytes that neither group nor others may read or write (chmod 600), through the descriptor
//! whose type, mode and size were checked. Throws Error naming the file and the reason.
inline SecureKey load_key_file(const std::string& path) {
  RegularFile file(path, "key file", /*follow_symlinks=*/false);
  check_key_file_mode(file.mode(), path);
  check_key_file_owner(file.owner(), ::geteuid(), path);
  check_key_directory(path);
  if (file.size() != SecureKey::size) detail::refuse_key_length(path, file.size());
  file.limit(SecureKey::size, "a key file holds exactly 32 bytes");  // it may not grow either
  struct Buffer {  // wiped however the function ends
    std::array<std::byte, SecureKey::size> bytes{};
    ~Buffer() { sodium_memzero(bytes.data(), bytes.size()); }
  } buffer;
  std::size_t got = 0;
  while (got < buffer.bytes.size()) {
    const std::size_t n = file.read(buffer.bytes.data() + got, buffer.bytes.size() - got);
    if (n == 0) break;  // it shrank: key_from_bytes names the length
    got += n;
  }
  char more = 0;
  (void)file.read(&more, 1);  // a byte beyond 32: the limit refuses it
  return key_from_bytes(std::span<const std::byte>(buffer.bytes.data(), got), path);
}

//! The key ring of the key files `paths`: one, or two while a key is changed over (the key in
//! use and its successor), each read with load_key_file. With `description`, writes there
//! "PATH (id HEX), ..." for a program's first lines. Throws Error.
inline KeyRing load_key_ring(const std::vector<std::string>& paths,
                             std::string* description = nullptr) {
  if (paths.empty() || paths.size() > KeyRing::max_keys) {
    ENDOHAPTICS_THROW(
        Error("key files: one, or two while a key is changed over (the key in use "
              "and its successor), got " +
              std::to_string(paths.size())));
  }
  KeyRing ring;
  std::string text;
  for (const auto& path : paths) {
    const SecureKey key = load_key_file(path);
    ring.add(key);
    text += (text.empty() ? "" : ", ") + path + " (id " + to_hex(key.id()) + ")";
  }
  if (description != nullptr) *description = text;
  return ring;
}

}  // namespace endohaptics::protocol
