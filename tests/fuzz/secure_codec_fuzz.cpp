// Fuzz target for protocol v2 (SecureCodec, SecureInitiator, SecureResponder, ReplayWindow).
// Byte 0 of the input selects how the rest is used:
//   even: the rest is a datagram as received, checked as a setpoint and as a state by the codec
//         and by both session sides (almost always `forged`: the tag guards everything);
//   odd:  the rest is re-tagged with the fuzz key first, so the fuzzer reaches what lies behind
//         the tag: version, type, sessions, the replay window and the 2016 payload checks.
// Invariants (abort on violation): anything that opens re-seals to the same bytes; a refused
// datagram changes no output and no session state; an unbound setpoint is delivered with every
// motor disabled.
#include <endohaptics/protocol/secure_session.hpp>

#include <algorithm>
#include <array>
#include <chrono>
#include <cstdint>
#include <cstdlib>
#include <cstring>
#include <span>

namespace {

namespace protocol = endohaptics::protocol;
using Codec = protocol::SecureCodec<4>;

const protocol::SecureKey& fuzz_key() {
  static const protocol::SecureKey key = [] {
    std::array<std::byte, protocol::SecureKey::size> k{};
    for (std::size_t i = 0; i < k.size(); ++i) k[i] = std::byte{static_cast<std::uint8_t>(i)};
    return protocol::SecureKey(k);
  }();
  return key;
}

void require(bool ok) {
  if (!ok) std::abort();
}

template <typename Session>
void check_session(Session& session, std::span<const std::byte> bytes, std::uint64_t now_ns) {
  const auto window = session.window();
  const auto own = session.session();
  std::array<std::byte, Session::receive_payload_size> payload{};
  payload.fill(std::byte{0xA5});
  const auto before = payload;
  protocol::SecureStatus s;
  if constexpr (requires { session.open(bytes, payload, std::chrono::nanoseconds(0)); }) {
    s = session.open(bytes, payload, std::chrono::nanoseconds(now_ns));
  } else {
    s = session.open(bytes, payload);
  }
  if (s != protocol::SecureStatus::ok && s != protocol::SecureStatus::unbound) {
    require(payload == before);
    require(session.window() == window);
    require(session.session() == own);
  }
  if (s == protocol::SecureStatus::unbound) require(payload.back() == std::byte{0});
}

void check_codec(std::span<const std::byte> bytes) {
  for (const auto type : {protocol::PacketType::setpoint, protocol::PacketType::state}) {
    protocol::SecureHeader header{};
    header.session = 0x5A5A;
    const protocol::SecureHeader untouched = header;
    std::span<const std::byte> payload;
    const protocol::SecureStatus s = Codec::open(fuzz_key(), type, bytes, header, payload);
    if (s != protocol::SecureStatus::ok) {
      require(header == untouched && payload.empty());
      continue;
    }
    std::array<std::byte, Codec::max_packet_size> again{};
    const auto out = std::span(again).first(Codec::packet_size(type));
    require(Codec::seal(fuzz_key(), header, payload, out) == protocol::SecureStatus::ok);
    require(std::memcmp(out.data(), bytes.data(), out.size()) == 0);
  }
}

struct Sessions {
  protocol::SecureInitiator<4> pc;
  protocol::SecureResponder<4> sbrio;
};

// Three exchanges of all-zero 2016 packets (valid: positions 0, every motor disabled): the first
// is answered unbound, the second binds, the third is obeyed.
Sessions bound_sessions() {
  Sessions s{protocol::SecureInitiator<4>(fuzz_key(), 0x11),
             protocol::SecureResponder<4>(fuzz_key(), 0x22)};
  const std::array<std::byte, Codec::Legacy::setpoint_packet_size> setpoint{};
  const std::array<std::byte, Codec::Legacy::state_packet_size> state{};
  std::array<std::byte, Codec::setpoint_packet_size> to_sbrio{};
  std::array<std::byte, Codec::state_packet_size> to_pc{};
  std::array<std::byte, Codec::Legacy::setpoint_packet_size> got_setpoint{};
  std::array<std::byte, Codec::Legacy::state_packet_size> got_state{};
  for (int i = 0; i < 3; ++i) {
    require(s.pc.seal(setpoint, to_sbrio) == protocol::SecureStatus::ok);
    const auto heard = s.sbrio.open(to_sbrio, got_setpoint, std::chrono::nanoseconds(0));
    require(heard == (i == 0 ? protocol::SecureStatus::unbound : protocol::SecureStatus::ok));
    require(s.sbrio.seal(state, to_pc) == protocol::SecureStatus::ok);
    require(s.pc.open(to_pc, got_state) == protocol::SecureStatus::ok);
  }
  require(s.sbrio.bound() && s.sbrio.peer_session() == 0x11 && s.pc.peer_session() == 0x22);
  return s;
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  if (size == 0) return 0;
  const bool retag = (data[0] & 1u) != 0;
  std::array<std::byte, 256> buffer{};
  const std::size_t n = std::min(size - 1, buffer.size());
  std::memcpy(buffer.data(), data + 1, n);
  auto bytes = std::span<std::byte>(buffer.data(), n);
  if (retag && n > Codec::tag_size) {
    fuzz_key().tag(bytes.first(n - Codec::tag_size),
                   bytes.subspan(n - Codec::tag_size).first<Codec::tag_size>());
  }
  check_codec(bytes);
  // Sessions in a known state (a PC that has sent three setpoints and bound sbRIO session 0x22,
  // an sbRIO bound to PC session 0x11 at time 0, sequence up to 3) and fresh ones; the sbRIO
  // side sees the datagram at a time taken from byte 0, sometimes past its 100 ms expiry.
  static const Sessions bound = bound_sessions();
  static const Sessions fresh{protocol::SecureInitiator<4>(fuzz_key(), 0x11),
                              protocol::SecureResponder<4>(fuzz_key(), 0x22)};
  const std::uint64_t now = static_cast<std::uint64_t>(data[0] >> 1) * 2'000'000;  // 0..254 ms
  for (const Sessions* start : {&bound, &fresh}) {
    Sessions s = *start;
    check_session(s.pc, bytes, 0);
    check_session(s.sbrio, bytes, now);
  }
  return 0;
}
