//! @file
//! Every file the library reads is opened here (configuration time): only a regular file (a
//! FIFO, device, socket or directory is refused before a byte is read, and opening never blocks:
//! O_NONBLOCK), at most a stated number of bytes (the size checked once open, the bytes counted
//! while reading), read through the one descriptor that was checked (no second open by name).
//! POSIX. Throws endohaptics::Error naming the file, what it is, its size and the limit.
#pragma once

#include <fcntl.h>
#include <sys/stat.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <cstddef>
#include <cstdint>
#include <cstring>
#include <limits>
#include <string>
#include <string_view>
#include <utility>

#include "endohaptics/core/error.hpp"

namespace endohaptics {

//! What a file of mode `mode` is, for messages: "a FIFO", "a character device", ...
[[nodiscard]] inline std::string_view file_type_name(mode_t mode) noexcept {
  if (S_ISREG(mode)) return "a regular file";
  if (S_ISDIR(mode)) return "a directory";
  if (S_ISFIFO(mode)) return "a FIFO (named pipe)";
  if (S_ISCHR(mode)) return "a character device";
  if (S_ISBLK(mode)) return "a block device";
  if (S_ISSOCK(mode)) return "a socket";
  if (S_ISLNK(mode)) return "a symbolic link";
  return "of an unknown type";
}

//! A regular file open for reading, with the limit of bytes it may hold. Move-only; closes the
//! descriptor when destroyed.
class RegularFile {
 public:
  //! No limit: `limit()` sets one.
  static constexpr std::uint64_t unlimited = std::numeric_limits<std::uint64_t>::max();

  //! Opens `path` read-only (O_NONBLOCK, O_CLOEXEC, O_NOCTTY; O_NOFOLLOW unless
  //! `follow_symlinks`) and refuses anything but a regular file, before and after opening (the
  //! type is checked on the name first, so that a device is not even opened, then on the open
  //! descriptor, which is what is read). `what` names the file in messages ("read_csv: log file",
  //! "key file"): "<what> '<path>' is a FIFO (named pipe), not a regular file".
  RegularFile(std::string path, std::string_view what, bool follow_symlinks = true)
      : path_(std::move(path)), what_(what) {
    struct stat st {};
    if ((follow_symlinks ? ::stat(path_.c_str(), &st) : ::lstat(path_.c_str(), &st)) != 0) {
      fail_open(errno);
    }
    refuse_unless_regular(st.st_mode);
    const int flags =
        O_RDONLY | O_NONBLOCK | O_CLOEXEC | O_NOCTTY | (follow_symlinks ? 0 : O_NOFOLLOW);
    do {
      fd_ = ::open(path_.c_str(), flags);
    } while (fd_ < 0 && errno == EINTR);
    if (fd_ < 0) fail_open(errno);
    if (::fstat(fd_, &st) != 0) fail(errno, "cannot be examined (fstat)");
    refuse_unless_regular(st.st_mode);
    // A regular file never blocks; reads behave as without O_NONBLOCK everywhere.
    if (const int fl = ::fcntl(fd_, F_GETFL); fl >= 0)
      (void)::fcntl(fd_, F_SETFL, fl & ~O_NONBLOCK);
    size_ = static_cast<std::uint64_t>(st.st_size);
    mode_ = st.st_mode;
    owner_ = st.st_uid;
  }
  ~RegularFile() {
    if (fd_ >= 0) ::close(fd_);
  }
  //! Takes over the descriptor of `other` (left closed).
  RegularFile(RegularFile&& other) noexcept
      : path_(std::move(other.path_)),
        what_(std::move(other.what_)),
        fd_(std::exchange(other.fd_, -1)),
        size_(other.size_),
        mode_(other.mode_),
        owner_(other.owner_),
        limit_(other.limit_),
        limit_hint_(std::move(other.limit_hint_)),
        read_(other.read_) {}
  RegularFile& operator=(RegularFile&&) = delete;
  RegularFile(const RegularFile&) = delete;
  RegularFile& operator=(const RegularFile&) = delete;

  //! Refuses the file when it holds more than `max_bytes` now, and makes `read` refuse it when
  //! it grows beyond them while being read. `raise` says how to raise the limit, for the message
  //! ("raise LogReadOptions::max_bytes to read it"): "<what> '<path>' holds N bytes, more than
  //! the limit of M bytes (<raise>)".
  void limit(std::uint64_t max_bytes, std::string_view raise) {
    limit_ = max_bytes;
    limit_hint_ = raise;
    if (size_ > limit_) {
      fail(0, "holds " + std::to_string(size_) + " bytes, more than the limit of " +
                  std::to_string(limit_) + " bytes" + hint());
    }
  }

  //! Reads up to `n` bytes into `out`: how many, 0 at the end of the file. Throws Error on a
  //! read error, or when the bytes read so far exceed the limit (the file grew).
  [[nodiscard]] std::size_t read(void* out, std::size_t n) {
    ssize_t got = 0;
    do {
      got = ::read(fd_, out, n);
    } while (got < 0 && errno == EINTR);
    if (got < 0) fail(errno, "cannot be read");
    read_ += static_cast<std::uint64_t>(got);
    if (read_ > limit_) {
      fail(0, "grew beyond the limit of " + std::to_string(limit_) + " bytes while being read" +
                  hint());
    }
    return static_cast<std::size_t>(got);
  }

  //! The rest of the file (all of it when nothing was read yet), within the limit.
  [[nodiscard]] std::string read_all() {
    std::string text;
    // The size from fstat, within the limit: one allocation for a file that does not grow.
    text.resize(static_cast<std::size_t>(std::min<std::uint64_t>(size_, limit_)) + 1);
    std::size_t used = 0;
    for (;;) {
      if (used == text.size()) {  // the file grew: at most to one byte beyond the limit
        const std::uint64_t doubled = std::max<std::uint64_t>(2 * text.size(), 4096);
        text.resize(static_cast<std::size_t>(
            limit_ == unlimited ? doubled : std::min<std::uint64_t>(doubled, limit_ + 1)));
      }
      const std::size_t got = read(text.data() + used, text.size() - used);
      if (got == 0) break;
      used += got;
    }
    text.resize(used);
    return text;
  }

  //! The path as given.
  [[nodiscard]] const std::string& path() const noexcept { return path_; }
  //! "<what> '<path>'": how messages name the file.
  [[nodiscard]] std::string name() const { return what_ + " '" + path_ + "'"; }
  //! Bytes, as fstat reported them when the file was opened.
  [[nodiscard]] std::uint64_t size() const noexcept { return size_; }
  //! The file's mode (type and permission bits) when it was opened.
  [[nodiscard]] mode_t mode() const noexcept { return mode_; }
  //! The owner (st_uid) of the file opened.
  [[nodiscard]] uid_t owner() const noexcept { return owner_; }
  //! Bytes read so far.
  [[nodiscard]] std::uint64_t bytes_read() const noexcept { return read_; }

 private:
  [[noreturn]] void fail(int err, const std::string& what) const {
    std::string m = name() + " " + what;
    if (err != 0) m += ": " + std::string(std::strerror(err));
    ENDOHAPTICS_THROW(Error(m));
  }
  [[noreturn]] void fail_open(int err) const {
    if (err == ENOENT) fail(0, "cannot be opened: the file does not exist");
    if (err == ELOOP) fail(0, "is a symbolic link, not a regular file");
    fail(err, "cannot be opened");
  }
  void refuse_unless_regular(mode_t mode) const {
    if (!S_ISREG(mode)) fail(0, "is " + std::string(file_type_name(mode)) + ", not a regular file");
  }
  [[nodiscard]] std::string hint() const {
    return limit_hint_.empty() ? std::string() : " (" + limit_hint_ + ")";
  }

  std::string path_;
  std::string what_;
  int fd_ = -1;
  std::uint64_t size_ = 0;
  mode_t mode_ = 0;
  uid_t owner_ = 0;
  std::uint64_t limit_ = unlimited;
  std::string limit_hint_;
  std::uint64_t read_ = 0;
};

//! The whole regular file `path`, refused when it holds more than `max_bytes` (before reading,
//! or as soon as it grows beyond them). `what` and `raise` as in RegularFile.
[[nodiscard]] inline std::string read_regular_file(const std::string& path, std::string_view what,
                                                   std::uint64_t max_bytes,
                                                   std::string_view raise) {
  RegularFile file(path, what);
  file.limit(max_bytes, raise);
  return file.read_all();
}

}  // namespace endohaptics
