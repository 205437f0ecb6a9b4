//! @file
//! The protocol v2 handshake (docs/protocol.md, "Sessions"): HELLO (console -> robot) and
//! WELCOME (robot -> console), both 110 bytes and tagged with the long-term key, and the session
//! keys both sides derive from them: one key per direction, the keyed BLAKE2b (a PRF of the
//! long-term key) of a label, the direction, the key id, the rig id and both sides' fresh 32-byte
//! nonces. So no packet of an earlier session, of another rig or of another key ever verifies in
//! this one. Integers big-endian. Static, noexcept, allocation-free, safe on any input bytes.
#pragma once

#include <sodium.h>

#include <algorithm>
#include <array>
#include <boost/endian/conversion.hpp>
#include <cstddef>
#include <cstdint>
#include <cstring>
#include <span>
#include <string>
#include <string_view>

#include "endohaptics/core/error.hpp"
#include "endohaptics/protocol/secure_codec.hpp"

namespace endohaptics::protocol {

//! Bytes of a rig id: the robot side's name, UTF-8, zero-padded.
inline constexpr std::size_t rig_id_size = 16;
//! The rig name both programs use unless told another (`--rig`): a lab with several rigs sharing
//! a key names each.
inline constexpr std::string_view default_rig_name = "sbrio";
//! A rig (robot side) identity, bound into every session key: a console for rig A cannot be
//! spliced to robot B even when both hold the same key.
using RigId = std::array<std::byte, rig_id_size>;
//! Bytes of a handshake nonce (libsodium randombytes_buf, fresh for every handshake).
inline constexpr std::size_t nonce_size = 32;
//! A handshake nonce.
using Nonce = std::array<std::byte, nonce_size>;

//! The rig id of `name`: 1 to 16 bytes, printable ASCII (so it reads the same in every log).
//! Configuration time: throws Error naming the rule.
[[nodiscard]] inline RigId make_rig_id(std::string_view name) {
  if (name.empty() || name.size() > rig_id_size) {
    ENDOHAPTICS_THROW(Error("rig name must be 1 to " + std::to_string(rig_id_size) +
                            " characters, got " + std::to_string(name.size())));
  }
  for (const char c : name) {
    if (c < 0x21 || c > 0x7E) {
      ENDOHAPTICS_THROW(Error("rig name must be printable ASCII without spaces, got '" +
                              std::string(name) + "'"));
    }
  }
  RigId id{};
  std::memcpy(id.data(), name.data(), name.size());
  return id;
}

//! The name a rig id holds (its bytes up to the first zero). Allocates: not for the tick.
[[nodiscard]] inline std::string rig_name(const RigId& id) {
  std::string s;
  for (const std::byte b : id) {
    if (b == std::byte{0}) break;
    const auto c = std::to_integer<unsigned char>(b);
    s += (c >= 0x21 && c <= 0x7E) ? static_cast<char>(c) : '?';
  }
  return s;
}

//! Lower-case hex of `bytes` (key ids in logs). Allocates: not for the tick.
[[nodiscard]] inline std::string to_hex(std::span<const std::byte> bytes) {
  static constexpr char digits[] = "0123456789abcdef";
  std::string s;
  for (const std::byte b : bytes) {
    s += digits[std::to_integer<unsigned>(b) >> 4];
    s += digits[std::to_integer<unsigned>(b) & 0xF];
  }
  return s;
}

//! HELLO: the console asks for a session.
struct Hello {
  KeyId key_id{};  //!< bytes 2..9: which long-term key tags it (the robot may hold two)
  RigId rig{};     //!< bytes 10..25: the robot side it is meant for
  //! bytes 26..33: ns since the Unix epoch, strictly increasing per console: the robot answers
  //! only a HELLO newer than every one it answered before (a recorded HELLO gets no answer)
  std::uint64_t timestamp = 0;
  Nonce nonce{};  //!< bytes 34..65: the console's fresh nonce
  //! bytes 66..69: µs, the longest round trip the console asks the robot to accept
  std::uint32_t max_round_trip_us = 0;
  //! Member-wise equality.
  friend bool operator==(const Hello&, const Hello&) = default;
};

//! WELCOME: the robot's answer to a HELLO, opening a pending session.
struct Welcome {
  KeyId key_id{};         //!< bytes 2..9: the key of the HELLO it answers
  RigId rig{};            //!< bytes 10..25: this robot side's identity
  Nonce console_nonce{};  //!< bytes 26..57: the HELLO's nonce, echoed (binds the answer)
  Nonce robot_nonce{};    //!< bytes 58..89: the robot's fresh nonce
  //! bytes 90..93: µs, the round trip the robot granted (at most what the HELLO asked)
  std::uint32_t max_round_trip_us = 0;
  //! Member-wise equality.
  friend bool operator==(const Welcome&, const Welcome&) = default;
};

//! Encoder/decoder of the two handshake packets. A HELLO is zero-padded to the WELCOME's size,
//! so the robot's answer is never larger than the request (no amplification).
class HandshakeCodec {
 public:
  static constexpr std::uint8_t version = 2;                    //!< byte 0
  static constexpr std::size_t tag_size = SecureKey::tag_size;  //!< bytes of tag, at the end
  static constexpr std::size_t packet_size = 110;               //!< bytes of HELLO and WELCOME
  //! Byte where a HELLO's zero padding starts.
  static constexpr std::size_t hello_padding_begin = 70;
  //! Packet bytes.
  using Bytes = std::array<std::byte, packet_size>;

  //! The key id a handshake packet names (unauthenticated: to choose the key its tag is checked
  //! with). wrong_size or wrong_type when it cannot be a handshake of `type`.
  [[nodiscard]] static SecureStatus peek_key_id(std::span<const std::byte> bytes, PacketType type,
                                                KeyId& id) noexcept {
    if (bytes.size() != packet_size) return SecureStatus::wrong_size;
    if (std::to_integer<std::uint8_t>(bytes[1]) != static_cast<std::uint8_t>(type)) {
      return SecureStatus::wrong_type;
    }
    std::memcpy(id.data(), bytes.data() + 2, id.size());
    return SecureStatus::ok;
  }

  //! Writes `hello` tagged with `key` into `out`.
  static void encode(const SecureKey& key, const Hello& hello,
                     std::span<std::byte, packet_size> out) noexcept {
    std::memset(out.data(), 0, out.size());
    start(out.data(), PacketType::hello, hello.key_id, hello.rig);
    store64(out.data() + 26, hello.timestamp);
    std::memcpy(out.data() + 34, hello.nonce.data(), nonce_size);
    store32(out.data() + 66, hello.max_round_trip_us);
    seal(key, out);
  }

  //! Writes `welcome` tagged with `key` into `out`.
  static void encode(const SecureKey& key, const Welcome& welcome,
                     std::span<std::byte, packet_size> out) noexcept {
    std::memset(out.data(), 0, out.size());
    start(out.data(), PacketType::welcome, welcome.key_id, welcome.rig);
    std::memcpy(out.data() + 26, welcome.console_nonce.data(), nonce_size);
    std::memcpy(out.data() + 58, welcome.robot_nonce.data(), nonce_size);
    store32(out.data() + 90, welcome.max_round_trip_us);
    seal(key, out);
  }

  //! Checks size, tag (forged), version, type and padding, in that order; on ok fills `hello`
  //! (untouched otherwise).
  [[nodiscard]] static SecureStatus decode(const SecureKey& key, std::span<const std::byte> bytes,
                                           Hello& hello) noexcept {
    if (const SecureStatus s = check(key, bytes, PacketType::hello); s != SecureStatus::ok)
      return s;
    if (std::any_of(bytes.begin() + hello_padding_begin, bytes.end() - tag_size,
                    [](std::byte b) { return b != std::byte{0}; })) {
      return SecureStatus::bad_payload;
    }
    Hello h;
    std::memcpy(h.key_id.data(), bytes.data() + 2, key_id_size);
    std::memcpy(h.rig.data(), bytes.data() + 10, rig_id_size);
    h.timestamp = load64(bytes.data() + 26);
    std::memcpy(h.nonce.data(), bytes.data() + 34, nonce_size);
    h.max_round_trip_us = load32(bytes.data() + 66);
    hello = h;
    return SecureStatus::ok;
  }

  //! Checks size, tag (forged), version and type; on ok fills `welcome` (untouched otherwise).
  [[nodiscard]] static SecureStatus decode(const SecureKey& key, std::span<const std::byte> bytes,
                                           Welcome& welcome) noexcept {
    if (const SecureStatus s = check(key, bytes, PacketType::welcome); s != SecureStatus::ok) {
      return s;
    }
    Welcome w;
    std::memcpy(w.key_id.data(), bytes.data() + 2, key_id_size);
    std::memcpy(w.rig.data(), bytes.data() + 10, rig_id_size);
    std::memcpy(w.console_nonce.data(), bytes.data() + 26, nonce_size);
    std::memcpy(w.robot_nonce.data(), bytes.data() + 58, nonce_size);
    w.max_round_trip_us = load32(bytes.data() + 90);
    welcome = w;
    return SecureStatus::ok;
  }

 private:
  static void start(std::byte* p, PacketType type, const KeyId& id, const RigId& rig) noexcept {
    p[0] = std::byte{version};
    p[1] = std::byte{static_cast<std::uint8_t>(type)};
    std::memcpy(p + 2, id.data(), id.size());
    std::memcpy(p + 10, rig.data(), rig.size());
  }
  static void seal(const SecureKey& key, std::span<std::byte, packet_size> out) noexcept {
    constexpr std::size_t body = packet_size - tag_size;
    key.tag(std::span<const std::byte>(out.data(), body),
            std::span<std::byte, tag_size>(out.data() + body, tag_size));
  }
  static SecureStatus check(const SecureKey& key, std::span<const std::byte> bytes,
                            PacketType type) noexcept {
    if (bytes.size() != packet_size) return SecureStatus::wrong_size;
    constexpr std::size_t body = packet_size - tag_size;
    if (!key.verify(bytes.first(body), bytes.subspan(body).first<tag_size>())) {
      return SecureStatus::forged;
    }
    if (std::to_integer<std::uint8_t>(bytes[0]) != version) return SecureStatus::bad_version;
    if (std::to_integer<std::uint8_t>(bytes[1]) != static_cast<std::uint8_t>(type)) {
      return SecureStatus::wrong_type;
    }
    return SecureStatus::ok;
  }
  static void store64(std::byte* p, std::uint64_t v) noexcept {
    boost::endian::store_big_u64(reinterpret_cast<unsigned char*>(p), v);
  }
  static void store32(std::byte* p, std::uint32_t v) noexcept {
    boost::endian::store_big_u32(reinterpret_cast<unsigned char*>(p), v);
  }
  static std::uint64_t load64(const std::byte* p) noexcept {
    return boost::endian::load_big_u64(reinterpret_cast<const unsigned char*>(p));
  }
  static std::uint32_t load32(const std::byte* p) noexcept {
    return boost::endian::load_big_u32(reinterpret_cast<const unsigned char*>(p));
  }
};

//! The label that opens every session key's derivation input.
inline constexpr std::string_view session_key_label = "endohaptics v2 session key";

//! Bytes of a session key's derivation input: label, direction, key id, rig id, two nonces.
inline constexpr std::size_t session_context_size =
    session_key_label.size() + 1 + key_id_size + rig_id_size + 2 * nonce_size;

//! Derives the session key of direction `direction` (setpoint: console -> robot; state: robot ->
//! console) into `out` (a key slot re-keyed in place: no allocation):
//! K = BLAKE2b-256(key = long-term key, label || direction byte || key id || rig id ||
//!     console nonce || robot nonce).
inline void derive_session_key(const SecureKey& long_term, PacketType direction, const RigId& rig,
                               const Nonce& console_nonce, const Nonce& robot_nonce,
                               SecureKey& out) noexcept {
  std::array<std::byte, session_context_size> context{};
  std::byte* p = context.data();
  std::memcpy(p, session_key_label.data(), session_key_label.size());
  p += session_key_label.size();
  *p++ = std::byte{static_cast<std::uint8_t>(direction)};
  std::memcpy(p, long_term.id().data(), key_id_size);
  p += key_id_size;
  std::memcpy(p, rig.data(), rig_id_size);
  p += rig_id_size;
  std::memcpy(p, console_nonce.data(), nonce_size);
  p += nonce_size;
  std::memcpy(p, robot_nonce.data(), nonce_size);
  std::array<std::byte, SecureKey::size> k{};
  long_term.derive(context, k);
  out.rekey(k);
  sodium_memzero(k.data(), k.size());
}

//! The session id a side's nonce gives it (its first 8 bytes, never 0): what the data packets'
//! session fields carry.
[[nodiscard]] inline std::uint64_t session_id_of(const Nonce& nonce) noexcept {
  const std::uint64_t id =
      boost::endian::load_big_u64(reinterpret_cast<const unsigned char*>(nonce.data()));
  return id == 0 ? 1 : id;
}

//! A fresh random nonce (randombytes_buf; libsodium is initialised by every SecureKey).
inline void fresh_nonce(Nonce& nonce) noexcept { randombytes_buf(nonce.data(), nonce.size()); }

}  // namespace endohaptics::protocol
