// endohaptics-v2-vectors: prints the protocol v2 test vectors of docs/protocol.md (key, header
// fields, 2016 payload, whole packet with its tag, in hex) and a replay-window trace, as computed
// by the library. tests/protocol/v2_vectors_check.py recomputes every packet with Python's
// hashlib.blake2b and its own packing, replays the window trace with its own RFC 4303 window, and
// checks that docs/protocol.md shows the same hex.
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

}  // namespace

int main() {
  std::array<std::byte, protocol::SecureKey::size> key_bytes{};
  for (std::size_t i = 0; i < key_bytes.size(); ++i) {
    key_bytes[i] = std::byte{static_cast<std::uint8_t>(i)};
  }
  print_hex("key", key_bytes);
  const protocol::SecureKey key(key_bytes);
  const std::uint64_t pc = 0x0123456789ABCDEFull;
  const std::uint64_t sbrio = 0xFEDCBA9876543210ull;

  Legacy::Setpoint setpoint;
  setpoint.position << 1.0, -0.75, 0.25, -0.25;
  setpoint.enable_mask = 0x0F;
  Legacy::State state;
  state.position << 1.0, -0.75, 0.25, -0.25;
  state.velocity << 0.5, 0.0, -1.5, 2.0;
  state.current << 0.125, 0.25, -0.375, 0.5;
  state.active_mask = 0x0F;

  int failures = 0;
  auto setpoint_vector = [&](const char* name, const protocol::SecureHeader& h,
                             const Legacy::Setpoint& s) {
    Legacy::SetpointBytes payload{};
    std::array<std::byte, Secure::setpoint_packet_size> packet{};
    if (Legacy::encode_setpoint(s, payload) != protocol::CodecStatus::ok ||
        Secure::seal(key, h, payload, packet) != protocol::SecureStatus::ok) {
      ++failures;
    }
    std::printf("vector %s\n", name);
    print_header(h);
    print_hex("payload", payload);
    print_hex("packet", packet);
  };
  auto state_vector = [&](const char* name, const protocol::SecureHeader& h) {
    Legacy::StateBytes payload{};
    std::array<std::byte, Secure::state_packet_size> packet{};
    if (Legacy::encode_state(state, payload) != protocol::CodecStatus::ok ||
        Secure::seal(key, h, payload, packet) != protocol::SecureStatus::ok) {
      ++failures;
    }
    std::printf("vector %s\n", name);
    print_header(h);
    print_hex("payload", payload);
    print_hex("packet", packet);
  };
  Legacy::Setpoint hello = setpoint;
  hello.enable_mask = 0;
  setpoint_vector("1-first-setpoint", {protocol::PacketType::setpoint, pc, 1, 0, 0}, hello);
  state_vector("2-state-answering-1", {protocol::PacketType::state, sbrio, 1, pc, 1});
  setpoint_vector("3-bound-setpoint", {protocol::PacketType::setpoint, pc, 2, sbrio, 1}, setpoint);
  state_vector("4-state-answering-2", {protocol::PacketType::state, sbrio, 2, pc, 2});

  // Replay window trace: sequence number, then the receiver's verdict (accepted when ok).
  protocol::ReplayWindow window;
  for (std::uint64_t s : {1ull, 2ull, 2ull, 5ull, 3ull, 4ull, 3ull, 0ull, 70ull, 7ull, 6ull, 8ull,
                          69ull, 70ull, 200ull, 137ull, 136ull, 137ull}) {
    std::printf("window %llu %s\n", static_cast<unsigned long long>(s),
                std::string(to_string(window.check_and_accept(s))).c_str());
  }
  return failures == 0 ? 0 : 1;
}
