#include "endohaptics/protocol/key_file.hpp"

#include <doctest/doctest.h>
#include <fcntl.h>
#include <sys/stat.h>
#include <unistd.h>

#include <array>
#include <chrono>
#include <cstddef>
#include <cstdio>
#include <cstdlib>
#include <future>
#include <initializer_list>
#include <string>
#include <vector>

namespace protocol_key_file_test {

namespace {

using endohaptics::Error;
using endohaptics::protocol::check_key_file_mode;
using endohaptics::protocol::generate_key_file;
using endohaptics::protocol::key_from_bytes;
using endohaptics::protocol::load_key_file;

// A fresh private directory, removed with what is in it.
struct TempDir {
  std::string path;
  TempDir() {
    char templ[] = "/tmp/endohaptics-key-test-XXXXXX";
    const char* made = ::mkdtemp(templ);
    REQUIRE(made != nullptr);
    path = made;
  }
  ~TempDir() {
    const std::string cmd = "rm -rf '" + path + "'";
    (void)std::system(cmd.c_str());
  }
  std::string file(const char* name) const { return path + "/" + name; }
};

void write_file(const std::string& path, const std::string& content, mode_t mode) {
  std::FILE* f = std::fopen(path.c_str(), "wb");
  REQUIRE(f != nullptr);
  REQUIRE(std::fwrite(content.data(), 1, content.size(), f) == content.size());
  REQUIRE(std::fclose(f) == 0);
  REQUIRE(::chmod(path.c_str(), mode) == 0);
}

}  // namespace

TEST_CASE("key file: generated with mode 0600, 32 bytes, loadable, never overwritten") {
  TempDir dir;
  const std::string path = dir.file("bridge.key");
  generate_key_file(path);
  struct stat st {};
  REQUIRE(::stat(path.c_str(), &st) == 0);
  CHECK((st.st_mode & 07777) == 0600);
  CHECK(st.st_size == 32);
  (void)load_key_file(path);
  CHECK_THROWS_WITH_AS(generate_key_file(path), doctest::Contains("refusing to overwrite"), Error);
  // Two keys differ (random source).
  const std::string other = dir.file("other.key");
  generate_key_file(other);
  std::array<char, 32> a{}, b{};
  std::FILE* fa = std::fopen(path.c_str(), "rb");
  std::FILE* fb = std::fopen(other.c_str(), "rb");
  REQUIRE((fa != nullptr && fb != nullptr));
  REQUIRE(std::fread(a.data(), 1, a.size(), fa) == 32);
  REQUIRE(std::fread(b.data(), 1, b.size(), fb) == 32);
  std::fclose(fa);
  std::fclose(fb);
  CHECK(a != b);
}

TEST_CASE("key file: generating through a symbolic link or into a missing directory fails") {
  TempDir dir;
  const std::string target = dir.file("target");
  const std::string link = dir.file("link.key");
  REQUIRE(::symlink(target.c_str(), link.c_str()) == 0);
  CHECK_THROWS_AS(generate_key_file(link), Error);
  CHECK(::access(target.c_str(), F_OK) != 0);  // nothing written behind the link
  CHECK_THROWS_WITH_AS(generate_key_file(dir.file("missing/dir.key")),
                       doctest::Contains("cannot create"), Error);
}

TEST_CASE("key file: refused when group or others may read it") {
  TempDir dir;
  const std::string path = dir.file("open.key");
  write_file(path, std::string(32, 'k'), 0640);
  CHECK_THROWS_WITH_AS(load_key_file(path), doctest::Contains("chmod 600"), Error);
  REQUIRE(::chmod(path.c_str(), 0604) == 0);
  CHECK_THROWS_WITH_AS(load_key_file(path), doctest::Contains("mode 0604"), Error);
  REQUIRE(::chmod(path.c_str(), 0400) == 0);
  (void)load_key_file(path);
}

TEST_CASE("key file: wrong length, missing file and directory are refused, naming the file") {
  TempDir dir;
  const std::string short_key = dir.file("short.key");
  write_file(short_key, std::string(31, 'k'), 0600);
  CHECK_THROWS_WITH_AS(load_key_file(short_key), doctest::Contains("holds 31"), Error);
  const std::string long_key = dir.file("long.key");
  write_file(long_key, std::string(33, 'k') + "\n", 0600);
  CHECK_THROWS_WITH_AS(load_key_file(long_key), doctest::Contains("exactly 32 bytes"), Error);
  CHECK_THROWS_WITH_AS(load_key_file(dir.file("absent.key")), doctest::Contains("absent.key"),
                       Error);
  REQUIRE(::chmod(dir.path.c_str(), 0700) == 0);
  CHECK_THROWS_WITH_AS(load_key_file(dir.path),
                       doctest::Contains("is a directory, not a regular file"), Error);
}

TEST_CASE("key file: error messages never contain the key") {
  TempDir dir;
  const std::string path = dir.file("secret.key");
  const std::string secret = "SECRETSECRETSECRETSECRETSECRET!!";
  write_file(path, secret, 0644);
  try {
    (void)load_key_file(path);
    FAIL("a world-readable key was loaded");
  } catch (const Error& e) {
    CHECK(std::string(e.what()).find("SECRET") == std::string::npos);
  }
}

TEST_CASE("key file: a FIFO, a device or a symbolic link is refused at once, never read") {
  // Before this check a FIFO as --key blocked the bridge in open() for ever.
  TempDir dir;
  const std::string fifo = dir.file("pipe.key");
  REQUIRE(::mkfifo(fifo.c_str(), 0600) == 0);
  auto result = std::async(std::launch::async, [&] {
    try {
      (void)load_key_file(fifo);
    } catch (const Error& e) {
      return std::string(e.what());
    }
    return std::string("(loaded)");
  });
  if (result.wait_for(std::chrono::seconds(5)) != std::future_status::ready) {
    const int fd = ::open(fifo.c_str(), O_WRONLY | O_NONBLOCK);  // lets the reader end
    if (fd >= 0) ::close(fd);
    FAIL("load_key_file blocked on a FIFO");
  }
  CHECK(result.get() == "key file '" + fifo + "' is a FIFO (named pipe), not a regular file");
  if (::access("/dev/zero", R_OK) == 0) {
    CHECK_THROWS_WITH_AS(
        load_key_file("/dev/zero"),
        doctest::Contains("key file '/dev/zero' is a character device, not a regular file"), Error);
  }
  // A symbolic link, even to a good key, is refused (O_NOFOLLOW).
  const std::string key = dir.file("good.key");
  write_file(key, std::string(32, 'k'), 0600);
  const std::string link = dir.file("link.key");
  REQUIRE(::symlink(key.c_str(), link.c_str()) == 0);
  CHECK_THROWS_WITH_AS(load_key_file(link),
                       doctest::Contains("is a symbolic link, not a regular file"), Error);
  (void)load_key_file(key);
}

TEST_CASE("key file: the checks on bytes and on the mode, apart from the file") {
  const std::vector<std::byte> bytes(33, std::byte{7});
  for (const std::size_t n : {std::size_t{0}, std::size_t{31}, std::size_t{33}}) {
    const std::string message = "must hold exactly 32 bytes, holds " + std::to_string(n);
    CHECK_THROWS_WITH_AS(key_from_bytes(std::span(bytes).first(n), "k"),
                         doctest::Contains(message.c_str()), Error);
  }
  (void)key_from_bytes(std::span(bytes).first(32), "k");
  for (const mode_t mode : std::initializer_list<mode_t>{0600, 0400, 0700, 04600}) {
    CHECK_NOTHROW(check_key_file_mode(mode, "k"));
  }
  for (const mode_t mode : std::initializer_list<mode_t>{0601, 0610, 0640, 0604, 0666, 0777}) {
    CHECK_THROWS_WITH_AS(check_key_file_mode(mode, "k"), doctest::Contains("chmod 600 k"), Error);
  }
}

TEST_CASE("key file: owned by the running user, in a directory only its owner may write") {
  using endohaptics::protocol::check_key_file_owner;
  // Before: a root bridge loaded a 0600 key owned by nobody (uid 65534).
  CHECK_THROWS_WITH_AS(check_key_file_owner(65534, 0, "k.key"),
                       doctest::Contains("is owned by uid 65534, not by the user running this (uid "
                                         "0): another account could replace the key"),
                       Error);
  CHECK_NOTHROW(check_key_file_owner(1000, 1000, "k.key"));
  TempDir dir;
  const std::string path = dir.file("open_dir.key");
  generate_key_file(path);
  CHECK_NOTHROW((void)load_key_file(path));
  // Before: a key in a world-writable directory (anyone could swap it between runs) loaded.
  REQUIRE(::chmod(dir.path.c_str(), 01777) == 0);
  CHECK_THROWS_WITH_AS((void)load_key_file(path),
                       doctest::Contains("lets group or others write there, so the key could be "
                                         "swapped"),
                       Error);
  REQUIRE(::chmod(dir.path.c_str(), 0770) == 0);
  CHECK_THROWS_AS((void)load_key_file(path), Error);
  REQUIRE(::chmod(dir.path.c_str(), 0700) == 0);
  CHECK_NOTHROW((void)load_key_file(path));
}

TEST_CASE("key ring: one or two key files, each named with its id, no more") {
  TempDir dir;
  const std::string a = dir.file("a.key"), b = dir.file("b.key"), c = dir.file("c.key");
  generate_key_file(a);
  generate_key_file(b);
  generate_key_file(c);
  std::string said;
  const auto ring = endohaptics::protocol::load_key_ring({a, b}, &said);
  CHECK(ring.size() == 2);
  const auto id = load_key_file(a).id();
  CHECK(ring.find(id).has_value());
  CHECK(said.find(a + " (id " + endohaptics::protocol::to_hex(id) + ")") == 0);
  CHECK_THROWS_WITH_AS((void)endohaptics::protocol::load_key_ring({a, b, c}),
                       doctest::Contains("got 3"), Error);
  CHECK_THROWS_WITH_AS((void)endohaptics::protocol::load_key_ring({}), doctest::Contains("got 0"),
                       Error);
  CHECK_THROWS_WITH_AS((void)endohaptics::protocol::load_key_ring({a, a}),
                       doctest::Contains("there already"), Error);
}

}  // namespace protocol_key_file_test
