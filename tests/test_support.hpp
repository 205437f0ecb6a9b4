// Helpers the unit tests share: the message of the endohaptics::Error a call throws, and temporary
// folders and files that clean up after themselves.
#pragma once

#include <filesystem>
#include <fstream>
#include <random>
#include <string>
#include <string_view>
#include <system_error>

#include "endohaptics/core/error.hpp"

namespace endohaptics::test {

//! The message of the endohaptics::Error that f() throws, or "(no exception)".
template <typename F>
std::string message_of(F&& f) {
  try {
    f();
  } catch (const Error& e) {
    return e.what();
  }
  return "(no exception)";
}

//! Writes `text` to `path` byte for byte (no newline translation).
inline void write_text(const std::filesystem::path& path, const std::string& text) {
  std::ofstream(path, std::ios::binary) << text;
}

//! A fresh folder under the system temp directory, removed with everything in it at scope exit.
//! Its name is `label` plus a random suffix, so test cases that CTest runs in parallel (one
//! process each) never share one.
class TempDir {
 public:
  explicit TempDir(std::string_view label = "test") {
    std::random_device rd;
    path_ = std::filesystem::temp_directory_path() /
            ("endohaptics-" + std::string(label) + "-" + std::to_string(rd()) + "-" +
             std::to_string(rd()));
    std::filesystem::create_directories(path_);
  }
  ~TempDir() {
    std::error_code ec;
    std::filesystem::remove_all(path_, ec);
  }
  TempDir(const TempDir&) = delete;
  TempDir& operator=(const TempDir&) = delete;

  //! The folder.
  [[nodiscard]] const std::filesystem::path& path() const noexcept { return path_; }

  //! Writes `content` byte for byte into the folder and returns the file's path.
  [[nodiscard]] std::string write(const std::string& name, const std::string& content) const {
    const std::filesystem::path p = path_ / name;
    write_text(p, content);
    return p.string();
  }

 private:
  std::filesystem::path path_;
};

//! One file `name` in a fresh TempDir (removed at scope exit): not created, or created holding
//! `content`.
struct TempFile {
  explicit TempFile(const std::string& name) : path(dir.path() / name) {}
  TempFile(const std::string& name, const std::string& content) : TempFile(name) {
    write_text(path, content);
  }

  TempDir dir;                 //!< the folder holding it
  std::filesystem::path path;  //!< the file
};

}  // namespace endohaptics::test
