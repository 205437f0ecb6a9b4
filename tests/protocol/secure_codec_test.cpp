#include "endohaptics/protocol/secure_codec.hpp"

#include <doctest/doctest.h>
#include <sodium.h>

#include <array>
#include <cstdint>
#include <cstring>
#include <utility>
#include <vector>

#include "alloc_counter.hpp"

namespace protocol_secure_codec_test {

namespace {

using endohaptics::protocol::PacketType;
using endohaptics::protocol::SecureCodec;
using endohaptics::protocol::SecureHeader;
using endohaptics::protocol::SecureKey;
using endohaptics::protocol::SecureStatus;
using Secure = SecureCodec<4>;
using Legacy = Secure::Legacy;

// The key of the docs/protocol.md test vectors: bytes 0x00, 0x01, ..., 0x1f.
SecureKey vector_key() {
  std::array<std::byte, SecureKey::size> k{};
  for (std::size_t i = 0; i < k.size(); ++i) k[i] = std::byte{static_cast<std::uint8_t>(i)};
  return SecureKey(k);
}

Legacy::Setpoint example_setpoint() {
  Legacy::Setpoint s;
  s.position << 1.0, -0.75, 0.25, -0.25;  // exact in float32: decode gives them back
  s.enable_mask = 0x0F;
  return s;
}

Legacy::State example_state() {
  Legacy::State s;
  s.position << 1.0, -0.75, 0.25, -0.25;
  s.velocity << 0.5, 0.0, -1.5, 2.0;
  s.current << 0.125, 0.25, -0.375, 0.5;
  s.active_mask = 0x0F;
  return s;
}

const SecureHeader setpoint_header{PacketType::setpoint, 0x0123456789ABCDEFull, 1,
                                   0xFEDCBA9876543210ull, 0};
const SecureHeader state_header{PacketType::state, 0xFEDCBA9876543210ull, 1, 0x0123456789ABCDEFull,
                                1};

std::string hex(std::span<const std::byte> b) {
  static const char* digits = "0123456789abcdef";
  std::string s;
  for (std::byte x : b) {
    s += digits[std::to_integer<unsigned>(x) >> 4];
    s += digits[std::to_integer<unsigned>(x) & 15u];
  }
  return s;
}

}  // namespace

TEST_CASE("SecureCodec: sizes (67-byte setpoint, 99-byte state for four motors)") {
  static_assert(Secure::header_size == 34 && Secure::tag_size == 16);
  static_assert(Secure::setpoint_packet_size == 34 + 17 + 16);
  static_assert(Secure::state_packet_size == 34 + 49 + 16);
  static_assert(SecureCodec<1>::setpoint_packet_size == 34 + 5 + 16);
  CHECK(Secure::packet_size(PacketType::state) == 99);
}

TEST_CASE("SecureCodec: setpoint and state round trip, header and 2016 payload bit for bit") {
  const SecureKey key = vector_key();
  std::array<std::byte, Secure::setpoint_packet_size> sp{};
  REQUIRE(Secure::encode_setpoint(key, setpoint_header, example_setpoint(), sp) ==
          SecureStatus::ok);
  // Layout: version, type, the three ids big-endian, then the 2016 packet unchanged.
  CHECK(std::to_integer<int>(sp[0]) == 2);
  CHECK(std::to_integer<int>(sp[1]) == 1);
  CHECK(hex(std::span(sp).subspan(2, 8)) == "0123456789abcdef");
  CHECK(hex(std::span(sp).subspan(10, 8)) == "0000000000000001");
  CHECK(hex(std::span(sp).subspan(18, 8)) == "fedcba9876543210");
  Legacy::SetpointBytes legacy{};
  REQUIRE(Legacy::encode_setpoint(example_setpoint(), legacy) ==
          endohaptics::protocol::CodecStatus::ok);
  CHECK(std::memcmp(sp.data() + 34, legacy.data(), legacy.size()) == 0);

  SecureHeader h;
  Legacy::Setpoint back;
  REQUIRE(Secure::decode_setpoint(key, sp, h, back) == SecureStatus::ok);
  CHECK(h == setpoint_header);
  CHECK(back == example_setpoint());

  std::array<std::byte, Secure::state_packet_size> st{};
  REQUIRE(Secure::encode_state(key, state_header, example_state(), st) == SecureStatus::ok);
  Legacy::State state;
  REQUIRE(Secure::decode_state(key, st, h, state) == SecureStatus::ok);
  CHECK(h == state_header);
  CHECK(state == example_state());
}

TEST_CASE("SecureCodec: the tag is keyed BLAKE2b-128 of every byte before it") {
  // Independent of SecureKey's precomputed state: libsodium's one-shot call on the same bytes.
  const SecureKey key = vector_key();
  std::array<std::byte, Secure::state_packet_size> st{};
  REQUIRE(Secure::encode_state(key, state_header, example_state(), st) == SecureStatus::ok);
  std::array<unsigned char, 32> raw_key{};
  for (std::size_t i = 0; i < raw_key.size(); ++i) raw_key[i] = static_cast<unsigned char>(i);
  std::array<unsigned char, 16> tag{};
  REQUIRE(crypto_generichash(tag.data(), tag.size(), reinterpret_cast<unsigned char*>(st.data()),
                             st.size() - 16, raw_key.data(), raw_key.size()) == 0);
  CHECK(std::memcmp(tag.data(), st.data() + st.size() - 16, 16) == 0);
}

TEST_CASE("SecureCodec: every single-bit flip of a valid packet is a forgery") {
  const SecureKey key = vector_key();
  std::array<std::byte, Secure::state_packet_size> st{};
  REQUIRE(Secure::encode_state(key, state_header, example_state(), st) == SecureStatus::ok);
  std::array<std::byte, Secure::setpoint_packet_size> sp{};
  REQUIRE(Secure::encode_setpoint(key, setpoint_header, example_setpoint(), sp) ==
          SecureStatus::ok);
  int flips = 0;
  for (std::size_t bit = 0; bit < st.size() * 8; ++bit) {
    auto bad = st;
    bad[bit / 8] ^= std::byte{static_cast<std::uint8_t>(1u << (bit % 8))};
    SecureHeader h = setpoint_header;
    Legacy::State out = example_state();
    out.active_mask = 3;
    const Legacy::State before = out;
    REQUIRE(Secure::decode_state(key, bad, h, out) == SecureStatus::forged);
    REQUIRE(h == setpoint_header);  // untouched
    REQUIRE(out == before);
    ++flips;
  }
  for (std::size_t bit = 0; bit < sp.size() * 8; ++bit) {
    auto bad = sp;
    bad[bit / 8] ^= std::byte{static_cast<std::uint8_t>(1u << (bit % 8))};
    SecureHeader h;
    Legacy::Setpoint out;
    REQUIRE(Secure::decode_setpoint(key, bad, h, out) == SecureStatus::forged);
    ++flips;
  }
  CHECK(flips == (99 + 67) * 8);
}

TEST_CASE("SecureCodec: every truncation and extension is a wrong size") {
  const SecureKey key = vector_key();
  std::array<std::byte, Secure::state_packet_size> st{};
  REQUIRE(Secure::encode_state(key, state_header, example_state(), st) == SecureStatus::ok);
  std::vector<std::byte> longer(st.begin(), st.end());
  longer.resize(st.size() + 16, std::byte{0});
  for (std::size_t n = 0; n <= longer.size(); ++n) {
    if (n == st.size()) continue;
    SecureHeader h;
    std::span<const std::byte> payload;
    REQUIRE(Secure::open(key, PacketType::state, std::span(longer).first(n), h, payload) ==
            SecureStatus::wrong_size);
    CHECK(payload.empty());
  }
  // A valid setpoint where a state is expected (and the reverse): wrong size.
  std::array<std::byte, Secure::setpoint_packet_size> sp{};
  REQUIRE(Secure::encode_setpoint(key, setpoint_header, example_setpoint(), sp) ==
          SecureStatus::ok);
  SecureHeader h;
  std::span<const std::byte> payload;
  CHECK(Secure::open(key, PacketType::state, sp, h, payload) == SecureStatus::wrong_size);
  CHECK(Secure::open(key, PacketType::setpoint, st, h, payload) == SecureStatus::wrong_size);
}

TEST_CASE("SecureCodec: another key is a forgery") {
  std::array<std::byte, SecureKey::size> k{};
  k[31] = std::byte{1};
  const SecureKey other(k);
  std::array<std::byte, Secure::setpoint_packet_size> sp{};
  REQUIRE(Secure::encode_setpoint(other, setpoint_header, example_setpoint(), sp) ==
          SecureStatus::ok);
  SecureHeader h;
  Legacy::Setpoint out;
  CHECK(Secure::decode_setpoint(vector_key(), sp, h, out) == SecureStatus::forged);
  CHECK(Secure::decode_setpoint(other, sp, h, out) == SecureStatus::ok);
}

TEST_CASE("SecureCodec: authentic packets of another version or type are told apart") {
  const SecureKey key = vector_key();
  std::array<std::byte, Secure::setpoint_packet_size> sp{};
  REQUIRE(Secure::encode_setpoint(key, setpoint_header, example_setpoint(), sp) ==
          SecureStatus::ok);
  auto retag = [&](std::array<std::byte, Secure::setpoint_packet_size> p) {
    key.tag(std::span<const std::byte>(p).first(p.size() - 16),
            std::span(p).subspan<Secure::setpoint_packet_size - 16>());
    return p;
  };
  auto v3 = sp;
  v3[0] = std::byte{3};
  SecureHeader h;
  Legacy::Setpoint out;
  CHECK(Secure::decode_setpoint(key, v3, h, out) == SecureStatus::forged);  // not retagged
  CHECK(Secure::decode_setpoint(key, retag(v3), h, out) == SecureStatus::bad_version);
  auto typed = sp;
  typed[1] = std::byte{2};
  CHECK(Secure::decode_setpoint(key, retag(typed), h, out) == SecureStatus::wrong_type);
  // An authentic packet whose 2016 payload is refused: bad_payload, output untouched.
  auto nan = sp;
  nan[34] = std::byte{0x7F};
  nan[35] = std::byte{0xC0};
  Legacy::Setpoint untouched;
  untouched.enable_mask = 1;
  out = untouched;
  CHECK(Secure::decode_setpoint(key, retag(nan), h, out) == SecureStatus::bad_payload);
  CHECK(out == untouched);
}

TEST_CASE("SecureCodec: seal refuses wrong payload and output sizes, output untouched") {
  const SecureKey key = vector_key();
  std::array<std::byte, 17> payload{};
  std::array<std::byte, 68> out{};
  out.fill(std::byte{0xAA});
  CHECK(Secure::seal(key, setpoint_header, payload, std::span(out)) == SecureStatus::wrong_size);
  CHECK(Secure::seal(key, setpoint_header, std::span(payload).first(16),
                     std::span(out).first(67)) == SecureStatus::wrong_size);
  for (std::byte b : out) REQUIRE(b == std::byte{0xAA});
  CHECK(Secure::seal(key, setpoint_header, payload, std::span(out).first(67)) == SecureStatus::ok);
  // A setpoint that the 2016 codec refuses is refused before anything is written.
  Legacy::Setpoint bad = example_setpoint();
  bad.enable_mask = 0x10;
  std::array<std::byte, Secure::setpoint_packet_size> sp{};
  CHECK(Secure::encode_setpoint(key, setpoint_header, bad, sp) == SecureStatus::bad_payload);
  for (std::byte b : sp) REQUIRE(b == std::byte{0});
}

TEST_CASE("SecureCodec: encode and verify+decode allocate nothing") {
  const SecureKey key = vector_key();
  std::array<std::byte, Secure::state_packet_size> st{};
  Legacy::State out;
  SecureHeader h;
  const long allocations = endohaptics::test::allocations_during([&] {
    for (int i = 0; i < 1000; ++i) {
      SecureHeader sh = state_header;
      sh.sequence = static_cast<std::uint64_t>(i + 1);
      REQUIRE(Secure::encode_state(key, sh, example_state(), st) == SecureStatus::ok);
      REQUIRE(Secure::decode_state(key, st, h, out) == SecureStatus::ok);
      st[5] ^= std::byte{1};
      REQUIRE(Secure::decode_state(key, st, h, out) == SecureStatus::forged);
    }
  });
  CHECK(allocations == 0);
}

}  // namespace protocol_secure_codec_test

namespace protocol_secure_codec_test_memory {

TEST_CASE("SecureKey: one locked copy: copies share it, a wipe reaches them all") {
  std::array<std::byte, endohaptics::protocol::SecureKey::size> bytes{};
  bytes[0] = std::byte{1};
  endohaptics::protocol::SecureKey key(bytes);
  const endohaptics::protocol::SecureKey copy = key;  // a handle, not a second copy
  const std::array<std::byte, 5> message{};
  std::array<std::byte, endohaptics::protocol::SecureKey::tag_size> tag{};
  copy.tag(message, tag);
  CHECK(key.verify(message, tag));
  key.wipe();
  CHECK_FALSE(copy.verify(message, tag));  // the one box is zeroed, for every handle
}

TEST_CASE("LockedBox: zero-initialised, movable, wiped on request") {
  struct Secret {
    std::array<unsigned char, 64> bytes;
  };
  endohaptics::protocol::LockedBox<Secret> box;
  for (unsigned char b : box->bytes) CHECK(b == 0);
  box->bytes[3] = 7;
  endohaptics::protocol::LockedBox<Secret> moved = std::move(box);
  CHECK(moved->bytes[3] == 7);
  moved.wipe();
  CHECK(moved->bytes[3] == 0);
  endohaptics::protocol::LockedBox<Secret> other;
  other->bytes[0] = 9;
  swap(moved, other);
  CHECK(moved->bytes[0] == 9);
}

}  // namespace protocol_secure_codec_test_memory
