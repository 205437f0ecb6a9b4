// endohaptics-v2-vectors: prints the protocol v2 test vectors of docs/protocol.md as computed by
// the library: the long-term key and its id, a HELLO and its WELCOME, the two session keys they
// give, three data packets of the session under those keys (header fields, 2016 payload, whole
// packet with its tag, in hex), and a replay-window trace. tests/protocol/v2_vectors_check.py
// recomputes every one of them with Python's hashlib.blake2b and its own packing, replays the
// window trace with its own RFC 4303 window, and checks that docs/protocol.md shows the same hex.
#include <endohaptics/protocol/handshake.hpp>
#include <endohaptics/protocol/replay_window.hpp>
#include <endohaptics/protocol/secure_codec.hpp>

#include <array>
#include <cstdint>
#include <cstdio>
#include <span>
#include <string>

namespace {

namespace protocol = endohaptics::protocol;
using Secure = protocol::SecureCodec<4>;
using Legacy = Secure::Legacy;

void print_hex(const char* label, std::span<const std::byte> bytes) {
  std::printf("%s ", label);
  for (std::byte b : bytes) std::printf("%02x", std::to_integer<unsigned>(b));
  std::printf("\n");
}

void print_header(const protocol::SecureHeader& h) {
  std::printf("type %u session %016llx sequence %llu peer_session %016llx ack %llu\n",
              static_cast<unsigned>(h.type), static_cast<unsigned long long>(h.session),
              static_cast<unsigned long long>(h.sequence),
              static_cast<unsigned long long>(h.peer_session),
              static_cast<unsigned long long>(h.ack));
}

template <std::size_t N>
std::array<std::byte, N> counting_from(unsigned first) {
  std::array<std::byte, N> a{};
  for (std::size_t i = 0; i < N; ++i) a[i] = std::byte{static_cast<std::uint8_t>(first + i)};
  return a;
}

}  // namespace

int main() {
  const auto key_bytes = counting_from<protocol::SecureKey::size>(0x00);
  print_hex("key", key_bytes);
  const protocol::SecureKey key(key_bytes);
  print_hex("key_id", key.id());

  // The handshake: fixed nonces and timestamp (a real run draws them at random).
  const protocol::RigId rig = protocol::make_rig_id("sbrio");
  const protocol::Nonce console_nonce = counting_from<protocol::nonce_size>(0x40);
  const protocol::Nonce robot_nonce = counting_from<protocol::nonce_size>(0x80);
  const protocol::Hello hello{key.id(), rig, 1764000000000000000ull, console_nonce, 200000};
  const protocol::Welcome welcome{key.id(), rig, console_nonce, robot_nonce, 100000};
  protocol::HandshakeCodec::Bytes packet{};
  protocol::HandshakeCodec::encode(key, hello, packet);
  std::printf("hello rig sbrio timestamp %llu max_round_trip_us %u\n",
              static_cast<unsigned long long>(hello.timestamp), hello.max_round_trip_us);
  print_hex("console_nonce", console_nonce);
  print_hex("packet", packet);
  protocol::HandshakeCodec::encode(key, welcome, packet);
  std::printf("welcome rig sbrio max_round_trip_us %u\n", welcome.max_round_trip_us);
  print_hex("robot_nonce", robot_nonce);
  print_hex("packet", packet);

  // The session keys, exported here only to print them (a session never shows its keys).
  protocol::SecureKey setpoint_key(counting_from<protocol::SecureKey::size>(0));
  protocol::SecureKey state_key(counting_from<protocol::SecureKey::size>(0));
  protocol::derive_session_key(key, protocol::PacketType::setpoint, rig, console_nonce, robot_nonce,
                               setpoint_key);
  protocol::derive_session_key(key, protocol::PacketType::state, rig, console_nonce, robot_nonce,
                               state_key);
  const std::uint64_t pc = protocol::session_id_of(console_nonce);
  const std::uint64_t robot = protocol::session_id_of(robot_nonce);

  Legacy::Setpoint setpoint;
  setpoint.position << 1.0, -0.75, 0.25, -0.25;
  setpoint.enable_mask = 0x0F;
  Legacy::State state;
  state.position << 1.0, -0.75, 0.25, -0.25;
  state.velocity << 0.5, 0.0, -1.5, 2.0;
  state.current << 0.125, 0.25, -0.375, 0.5;
  state.active_mask = 0x0F;

  int failures = 0;
  auto setpoint_vector = [&](const char* name, const protocol::SecureHeader& h) {
    Legacy::SetpointBytes payload{};
    std::array<std::byte, Secure::setpoint_packet_size> out{};
    if (Legacy::encode_setpoint(setpoint, payload) != protocol::CodecStatus::ok ||
        Secure::seal(setpoint_key, h, payload, out) != protocol::SecureStatus::ok) {
      ++failures;
    }
    std::printf("vector %s\n", name);
    print_header(h);
    print_hex("payload", payload);
    print_hex("packet", out);
  };
  auto state_vector = [&](const char* name, const protocol::SecureHeader& h) {
    Legacy::StateBytes payload{};
    std::array<std::byte, Secure::state_packet_size> out{};
    if (Legacy::encode_state(state, payload) != protocol::CodecStatus::ok ||
        Secure::seal(state_key, h, payload, out) != protocol::SecureStatus::ok) {
      ++failures;
    }
    std::printf("vector %s\n", name);
    print_header(h);
    print_hex("payload", payload);
    print_hex("packet", out);
  };
  setpoint_vector("3-first-setpoint", {protocol::PacketType::setpoint, pc, 1, robot, 0});
  state_vector("4-state-answering-1", {protocol::PacketType::state, robot, 1, pc, 1});
  setpoint_vector("5-second-setpoint", {protocol::PacketType::setpoint, pc, 2, robot, 1});

  // Replay window trace: sequence number, then the receiver's verdict (accepted when ok).
  protocol::ReplayWindow window;
  for (std::uint64_t s : {1ull, 2ull, 2ull, 5ull, 3ull, 4ull, 3ull, 0ull, 70ull, 7ull, 6ull, 8ull,
                          69ull, 70ull, 200ull, 137ull, 136ull, 137ull}) {
    std::printf("window %llu %s\n", static_cast<unsigned long long>(s),
                std::string(to_string(window.check_and_accept(s))).c_str());
  }
  return failures == 0 ? 0 : 1;
}
