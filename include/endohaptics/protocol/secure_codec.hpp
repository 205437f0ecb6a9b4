//! @file
//! SecureCodec: the v2 wire format on top of the unchanged 2016 PacketCodec: version byte, packet
//! type, sender session id, 64-bit sequence number, the peer's session id echoed, the sequence
//! number acknowledged (for a state: the setpoint it answers), the 2016 packet, then a 16-byte
//! keyed BLAKE2b tag (libsodium crypto_generichash) over all of it. Integers big-endian. Needs
//! libsodium (target endohaptics::secure_protocol). See docs/protocol.md, "Protocol v2".
#pragma once

#include <sodium.h>

#include <array>
#include <boost/endian/conversion.hpp>
#include <cstddef>
#include <cstdint>
#include <cstring>
#include <memory>
#include <span>
#include <string_view>
#include <utility>

#include "endohaptics/core/error.hpp"
#include "endohaptics/protocol/packet_codec.hpp"
#include "endohaptics/protocol/secure_memory.hpp"

namespace endohaptics::protocol {

//! Outcome of a v2 seal, open or session check. On anything but `ok` (and the handshake's
//! `hello` / `welcome`) the caller's outputs are left untouched.
enum class SecureStatus : std::uint8_t {
  ok = 0,         //!< authentic, fresh, in session: use it
  wrong_size,     //!< datagram length differs from the v2 packet size of the expected type
  forged,         //!< the tag does not verify: not sent by a holder of the key, or altered
  bad_version,    //!< authentic, but a protocol version other than 2
  wrong_type,     //!< authentic, but not the packet type expected here (e.g. a reflected packet)
  wrong_session,  //!< authentic, but for another or an earlier session (or another peer's run)
  replayed,       //!< authentic, in the replay window and already accepted (duplicate, replay)
  too_old,        //!< authentic, below the replay window (or sequence number 0)
  //! authentic, but answers too old: a state answering an older setpoint than the newest sent
  //! (allowed lag exceeded), or a setpoint acknowledging a state older than the round trip bound
  stale_answer,
  bad_payload,  //!< authentic, but the 2016 payload does not decode (NaN, mask bits)
  exhausted,    //!< send: the session's 2^64 - 1 sequence numbers are used up
  hello,        //!< robot side: an authentic, fresh handshake request: answer with a welcome
  welcome,      //!< console side: the robot's welcome to this attempt: a new session's keys
  no_session,   //!< a data packet while no session (nor a handshake) holds keys to check it
  wrong_key,    //!< a handshake naming a key id this side does not hold (or revoked)
  wrong_rig,    //!< an authentic handshake for another rig (robot) identity
};

//! Human-readable name of a status, for logs and counters.
[[nodiscard]] constexpr std::string_view to_string(SecureStatus status) noexcept {
  switch (status) {
    case SecureStatus::ok:
      return "ok";
    case SecureStatus::wrong_size:
      return "wrong size";
    case SecureStatus::forged:
      return "forged (bad tag)";
    case SecureStatus::bad_version:
      return "bad version";
    case SecureStatus::wrong_type:
      return "wrong packet type";
    case SecureStatus::wrong_session:
      return "wrong or stale session";
    case SecureStatus::replayed:
      return "duplicate or replay";
    case SecureStatus::too_old:
      return "older than the replay window";
    case SecureStatus::stale_answer:
      return "answers an older setpoint";
    case SecureStatus::bad_payload:
      return "bad 2016 payload";
    case SecureStatus::exhausted:
      return "sequence numbers exhausted";
    case SecureStatus::hello:
      return "handshake request";
    case SecureStatus::welcome:
      return "handshake answer";
    case SecureStatus::no_session:
      return "no session";
    case SecureStatus::wrong_key:
      return "unknown key id";
    case SecureStatus::wrong_rig:
      return "another rig";
  }
  return "unknown status";
}

//! The v2 packet types (byte 1 of every packet; covered by the tag, so no packet can be
//! reflected back to its sender as the other type).
enum class PacketType : std::uint8_t {
  setpoint = 1,  //!< PC -> sbRIO
  state = 2,     //!< sbRIO -> PC
  hello = 3,     //!< PC -> sbRIO: handshake request (protocol/handshake.hpp)
  welcome = 4,   //!< sbRIO -> PC: handshake answer (protocol/handshake.hpp)
};

//! The v2 header fields (bytes 0..33 of every packet).
struct SecureHeader {
  PacketType type = PacketType::setpoint;  //!< byte 1
  std::uint64_t session = 0;               //!< bytes 2..9: the sender's session id (random per run)
  std::uint64_t sequence = 0;              //!< bytes 10..17: the sender's sequence number, from 1
  std::uint64_t peer_session = 0;          //!< bytes 18..25: the receiver's session id (0: unknown)
  //! bytes 26..33: state: the sequence number of the setpoint it answers; setpoint: the highest
  //! state sequence number accepted (0: none).
  std::uint64_t ack = 0;

  //! Member-wise equality.
  friend bool operator==(const SecureHeader&, const SecureHeader&) = default;
};

//! Bytes of a key id: the first 8 bytes of the key's keyed BLAKE2b of "endohaptics v2 key id".
inline constexpr std::size_t key_id_size = 8;
//! A key id (not secret: it names a key without revealing it; docs/protocol.md, "Key ids").
using KeyId = std::array<std::byte, key_id_size>;

//! A 32-byte key, held as libsodium's keyed BLAKE2b states (so a packet costs the compression of
//! its own bytes only) in one LockedBox: locked in RAM, out of core dumps, wiped when the last
//! handle goes. Copies share that one box (one copy of the secret in memory). Never printed.
class SecureKey {
 public:
  static constexpr std::size_t size = 32;      //!< bytes of key (crypto_generichash_KEYBYTES)
  static constexpr std::size_t tag_size = 16;  //!< bytes of tag (crypto_generichash_BYTES_MIN)
  static_assert(size >= crypto_generichash_KEYBYTES_MIN && size <= crypto_generichash_KEYBYTES_MAX);
  static_assert(tag_size >= crypto_generichash_BYTES_MIN);

  //! Configuration time: initialises libsodium, allocates the locked box and keys the hash.
  //! Throws Error if libsodium cannot be initialised or locked memory cannot be had.
  explicit SecureKey(std::span<const std::byte, size> bytes)
      : states_(std::make_shared<LockedBox<States>>()) {
    rekey(bytes);
  }
  SecureKey(const SecureKey&) = default;                 //!< shares the one locked copy
  SecureKey& operator=(const SecureKey&) = default;      //!< shares the one locked copy
  SecureKey(SecureKey&&) noexcept = default;             //!< takes the handle
  SecureKey& operator=(SecureKey&&) noexcept = default;  //!< takes the handle
  ~SecureKey() = default;                                //!< the last handle frees the box

  //! Re-keys this key's box in place with `bytes` (a session key slot: allocation-free, so a
  //! handshake in the tick allocates nothing). Every copy sharing the box sees the new key.
  void rekey(std::span<const std::byte, size> bytes) noexcept {
    States& s = **states_;
    crypto_generichash_init(&s.tag, as_uchar(bytes.data()), size, tag_size);
    crypto_generichash_init(&s.kdf, as_uchar(bytes.data()), size, size);
    std::array<std::byte, size> id{};
    derive(std::as_bytes(std::span(key_id_label)), id);
    std::memcpy(id_.data(), id.data(), id_.size());
    sodium_memzero(id.data(), id.size());
  }

  //! Swaps the two keys' boxes and ids (no copy of the secrets, no allocation).
  friend void swap(SecureKey& a, SecureKey& b) noexcept {
    a.states_.swap(b.states_);
    std::swap(a.id_, b.id_);
  }

  //! Forgets the key (zeros the box: every tag then fails to verify against a real key's).
  void wipe() noexcept {
    states_->wipe();
    id_ = {};
  }

  //! This key's id (docs/protocol.md, "Key ids").
  [[nodiscard]] const KeyId& id() const noexcept { return id_; }

  //! Writes the tag of `message` into `tag`.
  void tag(std::span<const std::byte> message, std::span<std::byte, tag_size> tag) const noexcept {
    crypto_generichash_state state = (**states_).tag;
    crypto_generichash_update(&state, as_uchar(message.data()), message.size());
    crypto_generichash_final(&state, as_uchar(tag.data()), tag_size);
    sodium_memzero(&state, sizeof(state));
  }

  //! True when `tag` is the tag of `message` (compared in constant time, crypto_verify_16).
  [[nodiscard]] bool verify(std::span<const std::byte> message,
                            std::span<const std::byte, tag_size> tag) const noexcept {
    std::array<std::byte, tag_size> expected{};
    this->tag(message, expected);
    return crypto_verify_16(as_uchar(expected.data()), as_uchar(tag.data())) == 0;
  }

  //! Key derivation: the 32-byte keyed BLAKE2b of `context` (a PRF of the key) into `out`.
  void derive(std::span<const std::byte> context, std::span<std::byte, size> out) const noexcept {
    crypto_generichash_state state = (**states_).kdf;
    crypto_generichash_update(&state, as_uchar(context.data()), context.size());
    crypto_generichash_final(&state, as_uchar(out.data()), size);
    sodium_memzero(&state, sizeof(state));
  }

 private:
  static constexpr char key_id_label[21] = {'e', 'n', 'd', 'o', 'h', 'a', 'p', 't', 'i', 'c', 's',
                                            ' ', 'v', '2', ' ', 'k', 'e', 'y', ' ', 'i', 'd'};
  struct States {
    crypto_generichash_state tag;  // keyed, 16-byte output: packet tags
    crypto_generichash_state kdf;  // keyed, 32-byte output: key ids and session keys
  };
  static const unsigned char* as_uchar(const std::byte* p) noexcept {
    return reinterpret_cast<const unsigned char*>(p);
  }
  static unsigned char* as_uchar(std::byte* p) noexcept {
    return reinterpret_cast<unsigned char*>(p);
  }
  std::shared_ptr<LockedBox<States>> states_;
  KeyId id_{};
};

//! Bit-exact encoder/decoder of v2 packets for `NumMotors` motors: header, the 2016 packet of
//! PacketCodec<NumMotors>, tag. Static, noexcept, allocation-free, safe on any input bytes.
template <int NumMotors = 4>
class SecureCodec {
 public:
  using Legacy = PacketCodec<NumMotors>;                        //!< the 2016 payload codec
  static constexpr std::uint8_t version = 2;                    //!< byte 0
  static constexpr std::size_t header_size = 34;                //!< bytes before the payload
  static constexpr std::size_t tag_size = SecureKey::tag_size;  //!< bytes after the payload
  //! Bytes of a v2 setpoint packet (67 for four motors).
  static constexpr std::size_t setpoint_packet_size =
      header_size + Legacy::setpoint_packet_size + tag_size;
  //! Bytes of a v2 state packet (99 for four motors).
  static constexpr std::size_t state_packet_size =
      header_size + Legacy::state_packet_size + tag_size;
  //! Largest v2 packet.
  static constexpr std::size_t max_packet_size = state_packet_size;

  //! 2016 payload bytes of a packet of type `type`.
  [[nodiscard]] static constexpr std::size_t payload_size(PacketType type) noexcept {
    return type == PacketType::state ? Legacy::state_packet_size : Legacy::setpoint_packet_size;
  }
  //! Whole v2 packet bytes of type `type`.
  [[nodiscard]] static constexpr std::size_t packet_size(PacketType type) noexcept {
    return header_size + payload_size(type) + tag_size;
  }

  //! Writes header, `payload` (a 2016 packet of header.type) and the tag into `out`, which must
  //! be exactly packet_size(header.type) bytes; wrong_size otherwise (out untouched).
  [[nodiscard]] static SecureStatus seal(const SecureKey& key, const SecureHeader& header,
                                         std::span<const std::byte> payload,
                                         std::span<std::byte> out) noexcept {
    if (header.type != PacketType::setpoint && header.type != PacketType::state) {
      return SecureStatus::wrong_type;  // handshakes: HandshakeCodec (protocol/handshake.hpp)
    }
    if (payload.size() != payload_size(header.type) || out.size() != packet_size(header.type)) {
      return SecureStatus::wrong_size;
    }
    write_header(header, out.data());
    if (!payload.empty()) std::memmove(out.data() + header_size, payload.data(), payload.size());
    const std::size_t body = header_size + payload.size();
    key.tag(out.first(body), out.subspan(body).template first<tag_size>());
    return SecureStatus::ok;
  }

  //! Checks length (wrong_size), tag (forged), version (bad_version) and type (wrong_type), in
  //! that order, so any alteration of an authentic packet is `forged`. On ok writes the header
  //! and points `payload` at the 2016 packet inside `bytes`; otherwise both are untouched.
  [[nodiscard]] static SecureStatus open(const SecureKey& key, PacketType expected,
                                         std::span<const std::byte> bytes, SecureHeader& header,
                                         std::span<const std::byte>& payload) noexcept {
    if (expected != PacketType::setpoint && expected != PacketType::state) {
      return SecureStatus::wrong_type;  // handshakes: HandshakeCodec (protocol/handshake.hpp)
    }
    if (bytes.size() != packet_size(expected)) return SecureStatus::wrong_size;
    const std::size_t body = bytes.size() - tag_size;
    if (!key.verify(bytes.first(body), bytes.subspan(body).template first<tag_size>())) {
      return SecureStatus::forged;
    }
    if (std::to_integer<std::uint8_t>(bytes[0]) != version) return SecureStatus::bad_version;
    if (std::to_integer<std::uint8_t>(bytes[1]) != static_cast<std::uint8_t>(expected)) {
      return SecureStatus::wrong_type;
    }
    header.type = expected;
    header.session = load(bytes.data() + 2);
    header.sequence = load(bytes.data() + 10);
    header.peer_session = load(bytes.data() + 18);
    header.ack = load(bytes.data() + 26);
    payload = bytes.subspan(header_size, payload_size(expected));
    return SecureStatus::ok;
  }

  //! Typed: encodes `setpoint` with PacketCodec and seals it (header.type must be setpoint).
  //! bad_payload when the 2016 codec refuses the setpoint; `out` untouched then.
  [[nodiscard]] static SecureStatus encode_setpoint(
      const SecureKey& key, const SecureHeader& header, const typename Legacy::Setpoint& setpoint,
      std::span<std::byte, setpoint_packet_size> out) noexcept {
    if (header.type != PacketType::setpoint) return SecureStatus::wrong_type;
    typename Legacy::SetpointBytes payload{};
    if (Legacy::encode_setpoint(setpoint, payload) != CodecStatus::ok) {
      return SecureStatus::bad_payload;
    }
    return seal(key, header, payload, out);
  }

  //! Typed: encodes `state` with PacketCodec and seals it (header.type must be state).
  [[nodiscard]] static SecureStatus encode_state(
      const SecureKey& key, const SecureHeader& header, const typename Legacy::State& state,
      std::span<std::byte, state_packet_size> out) noexcept {
    if (header.type != PacketType::state) return SecureStatus::wrong_type;
    typename Legacy::StateBytes payload{};
    if (Legacy::encode_state(state, payload) != CodecStatus::ok) return SecureStatus::bad_payload;
    return seal(key, header, payload, out);
  }

  //! Typed: open() as a state packet, then the 2016 decode; outputs untouched unless ok.
  [[nodiscard]] static SecureStatus decode_state(const SecureKey& key,
                                                 std::span<const std::byte> bytes,
                                                 SecureHeader& header,
                                                 typename Legacy::State& state) noexcept {
    return decode<PacketType::state>(key, bytes, header, state);
  }

  //! Typed: open() as a setpoint packet, then the 2016 decode; outputs untouched unless ok.
  [[nodiscard]] static SecureStatus decode_setpoint(const SecureKey& key,
                                                    std::span<const std::byte> bytes,
                                                    SecureHeader& header,
                                                    typename Legacy::Setpoint& setpoint) noexcept {
    return decode<PacketType::setpoint>(key, bytes, header, setpoint);
  }

 private:
  template <PacketType Type, typename Out>
  static SecureStatus decode(const SecureKey& key, std::span<const std::byte> bytes,
                             SecureHeader& header, Out& out) noexcept {
    SecureHeader h;
    std::span<const std::byte> payload;
    if (const SecureStatus s = open(key, Type, bytes, h, payload); s != SecureStatus::ok) return s;
    CodecStatus c;
    if constexpr (Type == PacketType::state) {
      c = Legacy::decode_state(payload, out);
    } else {
      c = Legacy::decode_setpoint(payload, out);
    }
    if (c != CodecStatus::ok) return SecureStatus::bad_payload;
    header = h;
    return SecureStatus::ok;
  }

  static void write_header(const SecureHeader& h, std::byte* p) noexcept {
    p[0] = std::byte{version};
    p[1] = std::byte{static_cast<std::uint8_t>(h.type)};
    store(p + 2, h.session);
    store(p + 10, h.sequence);
    store(p + 18, h.peer_session);
    store(p + 26, h.ack);
  }
  static void store(std::byte* p, std::uint64_t v) noexcept {
    boost::endian::store_big_u64(reinterpret_cast<unsigned char*>(p), v);
  }
  static std::uint64_t load(const std::byte* p) noexcept {
    return boost::endian::load_big_u64(reinterpret_cast<const unsigned char*>(p));
  }
};

}  // namespace endohaptics::protocol
