// Fuzz target for protocol v2 (SecureCodec, HandshakeCodec, SecureInitiator, SecureResponder,
// ReplayWindow). Byte 0 of the input selects how the rest is used:
//   0 mod 3: the rest is a datagram as received: checked as a setpoint, a state, a HELLO and a
//            WELCOME by the codecs, and by fresh and connected session sides (almost always
//            `forged`: the tag guards everything);
//   1 mod 3: the rest is re-tagged with the long-term key first, so the fuzzer reaches what lies
//            behind it: version, type, the handshake's fields (key id, rig, timestamp, padding),
//            the sessions' checks and the 2016 payload checks;
//   2 mod 3: the rest is a script of operations on a console and a robot side over a link the
//            fuzzer controls (seal, deliver, reorder, replay, drop, delay, rekey, restart): it
//            reaches behind the session keys the way an attacker on the path would.
// Invariants (abort on violation): anything that opens re-seals to the same bytes; a refused
// datagram changes no output; the robot side never obeys a setpoint older than one it obeyed in
// the same session, nor anything outside a live session but the first setpoint of a new one, nor
// anything before a handshake; a WELCOME is never larger than its HELLO, and nothing but a HELLO
// is ever answered by one.
#include <endohaptics/protocol/secure_session.hpp>

#include <algorithm>
#include <array>
#include <chrono>
#include <cstdint>
#include <cstdlib>
#include <cstring>
#include <memory>
#include <span>
#include <vector>

namespace {

namespace protocol = endohaptics::protocol;
using Codec = protocol::SecureCodec<4>;
using Handshake = protocol::HandshakeCodec;
using namespace std::chrono_literals;

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

protocol::InitiatorConfig console_config() {
  protocol::InitiatorConfig c;
  c.rig = protocol::make_rig_id("fuzz");
  return c;
}

protocol::ResponderConfig robot_config() {
  protocol::ResponderConfig c;
  c.rig = protocol::make_rig_id("fuzz");
  c.max_round_trip = 50ms;
  return c;
}

template <typename Session>
protocol::SecureStatus check_session(Session& session, std::span<const std::byte> bytes,
                                     std::chrono::nanoseconds now) {
  std::array<std::byte, Session::receive_payload_size> payload{};
  payload.fill(std::byte{0xA5});
  const auto before = payload;
  const protocol::SecureStatus s = session.open(bytes, payload, now);
  if (s != protocol::SecureStatus::ok) require(payload == before);
  return s;
}

void check_codecs(std::span<const std::byte> bytes) {
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
  protocol::Hello hello{};
  if (Handshake::decode(fuzz_key(), bytes, hello) == protocol::SecureStatus::ok) {
    Handshake::Bytes again{};
    Handshake::encode(fuzz_key(), hello, again);
    require(std::memcmp(again.data(), bytes.data(), again.size()) == 0);
  }
  protocol::Welcome welcome{};
  if (Handshake::decode(fuzz_key(), bytes, welcome) == protocol::SecureStatus::ok) {
    Handshake::Bytes again{};
    Handshake::encode(fuzz_key(), welcome, again);
    require(std::memcmp(again.data(), bytes.data(), again.size()) == 0);
  }
}

// A console and a robot side, connected at time 0 (one setpoint obeyed, its state taken) or not.
struct Pair {
  protocol::SecureInitiator<4> pc{fuzz_key(), console_config()};
  protocol::SecureResponder<4> robot{fuzz_key(), robot_config()};

  void connect(std::chrono::nanoseconds now) {
    Handshake::Bytes hello{};
    require(pc.hello_due(now, hello));
    std::array<std::byte, Codec::Legacy::setpoint_packet_size> got{};
    require(robot.open(hello, got, now) == protocol::SecureStatus::hello);
    const auto welcome = robot.take_reply();
    require(welcome.size() == hello.size());
    std::array<std::byte, Codec::Legacy::state_packet_size> state{};
    require(pc.open(welcome, state, now) == protocol::SecureStatus::welcome);
  }
};

// The script mode: the robot side's obedience is checked against what the console sent.
void run_script(std::span<const std::byte> script) {
  Pair p;
  std::vector<std::vector<std::byte>> to_robot, to_console, recorded;
  std::chrono::nanoseconds now{0};
  // Per robot session: the highest setpoint sequence obeyed.
  std::uint64_t robot_sessions = 0, highest = 0;
  const std::array<std::byte, Codec::Legacy::setpoint_packet_size> setpoint{};
  const std::array<std::byte, Codec::Legacy::state_packet_size> state{};
  auto deliver_to_robot = [&](const std::vector<std::byte>& d) {
    const bool was_live = p.robot.live_at(now);
    const auto s = check_session(p.robot, d, now);
    if (s == protocol::SecureStatus::ok) {
      // Obeyed only in a live session, or as the first setpoint of a new one.
      require(was_live || p.robot.sessions() != robot_sessions);
      if (p.robot.sessions() != robot_sessions) {
        robot_sessions = p.robot.sessions();
        highest = 0;
      }
      const auto top = p.robot.window().top();
      require(top > highest);  // strictly newer than every setpoint obeyed in this session
      highest = top;
    }
    if (s == protocol::SecureStatus::hello) {
      const auto reply = p.robot.take_reply();
      require(reply.empty() || reply.size() == d.size());
      if (!reply.empty()) to_console.emplace_back(reply.begin(), reply.end());
    } else {
      require(p.robot.take_reply().empty());
    }
  };
  for (const std::byte b : script) {
    const unsigned op = std::to_integer<unsigned>(b);
    switch (op % 9) {
      case 0: {  // the console's tick: a HELLO when due, then a setpoint
        Handshake::Bytes hello{};
        if (p.pc.hello_due(now, hello)) to_robot.emplace_back(hello.begin(), hello.end());
        std::array<std::byte, Codec::setpoint_packet_size> out{};
        if (p.pc.seal(setpoint, out) == protocol::SecureStatus::ok) {
          to_robot.emplace_back(out.begin(), out.end());
        }
        break;
      }
      case 1:  // deliver the oldest datagram to the robot side (recorded by the attacker)
      case 2:  // deliver one out of order
        if (!to_robot.empty()) {
          const std::size_t i = op % 9 == 1 ? 0 : (op / 9) % to_robot.size();
          recorded.push_back(to_robot[i]);
          deliver_to_robot(to_robot[i]);
          to_robot.erase(to_robot.begin() + static_cast<std::ptrdiff_t>(i));
        }
        break;
      case 3:  // replay a recorded datagram
        if (!recorded.empty()) deliver_to_robot(recorded[(op / 9) % recorded.size()]);
        break;
      case 4:  // time passes: 1..28 ms
        now += std::chrono::milliseconds(1 + op / 9);
        break;
      case 5: {  // the robot answers the setpoint it obeyed last
        std::array<std::byte, Codec::state_packet_size> out{};
        if (p.robot.seal(state, out) == protocol::SecureStatus::ok) {
          to_console.emplace_back(out.begin(), out.end());
        }
        break;
      }
      case 6:  // deliver to the console, oldest first
        if (!to_console.empty()) {
          (void)check_session(p.pc, to_console.front(), now);
          to_console.erase(to_console.begin());
        }
        break;
      case 7:  // drop what is in flight
        (op / 9) % 2 == 0 ? to_robot.clear() : to_console.clear();
        break;
      case 8:  // the robot side restarts: it keeps nothing
        if (op / 9 == 0) {
          p.robot = protocol::SecureResponder<4>(fuzz_key(), robot_config());
          robot_sessions = 0;
          highest = 0;
        }
        break;
    }
  }
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  if (size == 0) return 0;
  const unsigned mode = data[0] % 3u;
  std::array<std::byte, 512> buffer{};
  const std::size_t n = std::min(size - 1, buffer.size());
  std::memcpy(buffer.data(), data + 1, n);
  auto bytes = std::span<std::byte>(buffer.data(), n);
  if (mode == 2) {
    run_script(bytes);
    return 0;
  }
  if (mode == 1 && n > Codec::tag_size) {
    fuzz_key().tag(bytes.first(n - Codec::tag_size),
                   bytes.subspan(n - Codec::tag_size).first<Codec::tag_size>());
  }
  check_codecs(bytes);
  // Fresh and connected sides; the datagram arrives at a time from byte 0 (0..170 ms), sometimes
  // past the robot side's 100 ms expiry.
  const auto now = std::chrono::milliseconds(data[0] / 3u * 2u);
  Pair fresh;
  (void)check_session(fresh.pc, bytes, now);
  require(check_session(fresh.robot, bytes, now) != protocol::SecureStatus::ok);
  Pair connected;
  connected.connect(0ms);
  (void)check_session(connected.pc, bytes, now);
  (void)check_session(connected.robot, bytes, now);
  return 0;
}
