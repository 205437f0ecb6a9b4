// Fuzz target for the key-file reader (protocol/key_file.hpp): the input is a key file's content.
// The checks on bytes and on a mode run on it directly (key_from_bytes; check_key_file_mode on a
// mode made of the input's first two bytes), and load_key_file reads it from a file this target
// writes with mode 0600 in a private folder (the file's mode is fixed: a refused mode never gets
// to the bytes). Both may refuse an input only with endohaptics::Error, and exactly when they
// should: a key is accepted when the input holds 32 bytes, and the two ways give the same key (the
// same tag on a message); a mode is refused when group or others have any permission.
#include <fcntl.h>
#include <sodium.h>
#include <stdlib.h>
#include <unistd.h>

#include <array>
#include <cstddef>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <endohaptics/protocol/key_file.hpp>
#include <optional>
#include <span>
#include <string>

namespace {

namespace protocol = endohaptics::protocol;

std::string g_dir;
std::string g_path;

void remove_dir() {
  ::unlink(g_path.c_str());
  ::rmdir(g_dir.c_str());
}

void write_key_file(const std::uint8_t* data, std::size_t size) {
  const int fd = ::open(g_path.c_str(), O_WRONLY | O_CREAT | O_TRUNC | O_CLOEXEC, 0600);
  if (fd < 0) std::abort();
  std::size_t done = 0;
  while (done < size) {
    const ssize_t n = ::write(fd, data + done, size - done);
    if (n <= 0) std::abort();
    done += static_cast<std::size_t>(n);
  }
  if (::fchmod(fd, 0600) != 0 || ::close(fd) != 0) std::abort();
}

std::array<std::byte, protocol::SecureKey::tag_size> tag_of(const protocol::SecureKey& key) {
  static constexpr std::array<std::byte, 4> message{std::byte{1}, std::byte{2}, std::byte{3},
                                                    std::byte{4}};
  std::array<std::byte, protocol::SecureKey::tag_size> tag{};
  key.tag(message, tag);
  return tag;
}

}  // namespace

extern "C" int LLVMFuzzerInitialize(int* /*argc*/, char*** /*argv*/) {
  if (sodium_init() < 0) {
    std::fprintf(stderr, "fuzz_key_file: libsodium failed to initialise\n");
    std::exit(2);
  }
  char templ[] = "/tmp/endohaptics-fuzz-key-XXXXXX";
  const char* made = ::mkdtemp(templ);
  if (made == nullptr) {
    std::perror("fuzz_key_file: mkdtemp");
    std::exit(2);
  }
  g_dir = made;
  g_path = g_dir + "/fuzz.key";
  std::atexit(remove_dir);
  return 0;
}

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const std::span<const std::byte> bytes(reinterpret_cast<const std::byte*>(data), size);
  const bool key_size = size == protocol::SecureKey::size;
  std::optional<protocol::SecureKey> direct;
  try {
    direct.emplace(protocol::key_from_bytes(bytes, "fuzz input"));
  } catch (const endohaptics::Error&) {
  }
  if (direct.has_value() != key_size) std::abort();

  if (size >= 2) {
    const auto mode = static_cast<mode_t>((data[0] | (data[1] << 8)) & 07777);
    bool accepted = true;
    try {
      protocol::check_key_file_mode(mode, "fuzz input");
    } catch (const endohaptics::Error&) {
      accepted = false;
    }
    if (accepted != ((mode & 077) == 0)) std::abort();
  }

  write_key_file(data, size);
  std::optional<protocol::SecureKey> loaded;
  try {
    loaded.emplace(protocol::load_key_file(g_path));
  } catch (const endohaptics::Error&) {
  }
  if (loaded.has_value() != key_size) std::abort();
  if (loaded && tag_of(*loaded) != tag_of(*direct)) std::abort();
  return 0;
}
