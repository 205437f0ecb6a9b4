#include "endohaptics/protocol/secure_session.hpp"

#include <doctest/doctest.h>

#include <array>
#include <chrono>
#include <cstdint>
#include <cstring>
#include <vector>

#include "alloc_counter.hpp"

namespace protocol_secure_session_test {

namespace {

using namespace std::chrono_literals;
using endohaptics::protocol::HandshakeCodec;
using endohaptics::protocol::InitiatorConfig;
using endohaptics::protocol::KeyRing;
using endohaptics::protocol::make_rig_id;
using endohaptics::protocol::ResponderConfig;
using endohaptics::protocol::SecureInitiator;
using endohaptics::protocol::SecureKey;
using endohaptics::protocol::SecureResponder;
using endohaptics::protocol::SecureStatus;
using Initiator = SecureInitiator<4>;
using Responder = SecureResponder<4>;
using SetpointPacket = std::array<std::byte, Initiator::send_packet_size>;
using StatePacket = std::array<std::byte, Responder::send_packet_size>;
using SetpointPayload = std::array<std::byte, Initiator::send_payload_size>;
using StatePayload = std::array<std::byte, Responder::send_payload_size>;
using Handshake = HandshakeCodec::Bytes;

SecureKey test_key(std::uint8_t seed = 7) {
  std::array<std::byte, SecureKey::size> k{};
  for (std::size_t i = 0; i < k.size(); ++i) k[i] = std::byte{static_cast<std::uint8_t>(seed + i)};
  return SecureKey(k);
}

InitiatorConfig console_config(const char* rig = "rig-a", std::uint64_t lag = 0) {
  InitiatorConfig c;
  c.rig = make_rig_id(rig);
  c.max_answer_lag = lag;
  return c;
}

ResponderConfig robot_config(const char* rig = "rig-a",
                             std::chrono::nanoseconds round_trip = 200ms) {
  ResponderConfig c;
  c.rig = make_rig_id(rig);
  c.max_round_trip = round_trip;
  return c;
}

// A 2016 setpoint payload: four zero floats, then `mask`.
SetpointPayload setpoint_payload(std::uint8_t mask) {
  SetpointPayload p{};
  p.back() = std::byte{mask};
  return p;
}

StatePayload state_payload(std::uint8_t marker) {
  StatePayload p{};
  p[3] = std::byte{marker};  // the low byte of position 0: tells answers apart
  p.back() = std::byte{0x0F};
  return p;
}

SetpointPacket next_setpoint(Initiator& pc, std::uint8_t mask = 0x0F) {
  SetpointPacket out{};
  REQUIRE(pc.seal(setpoint_payload(mask), out) == SecureStatus::ok);
  return out;
}

StatePacket answer(Responder& robot, std::uint8_t marker = 1) {
  StatePacket out{};
  REQUIRE(robot.seal(state_payload(marker), out) == SecureStatus::ok);
  return out;
}

// The console's HELLO due at `now` (REQUIREs one).
Handshake hello_at(Initiator& pc, std::chrono::nanoseconds now) {
  Handshake h{};
  REQUIRE(pc.hello_due(now, h));
  return h;
}

// The robot's answer to `hello` at `now` (REQUIREs a WELCOME).
Handshake welcome_for(Responder& robot, const Handshake& hello, std::chrono::nanoseconds now) {
  SetpointPayload unused{};
  REQUIRE(robot.open(hello, unused, now) == SecureStatus::hello);
  const auto reply = robot.take_reply();
  REQUIRE(reply.size() == HandshakeCodec::packet_size);
  Handshake w{};
  std::memcpy(w.data(), reply.data(), w.size());
  return w;
}

// HELLO, WELCOME, the first setpoint obeyed and its state taken, all at `now`.
void connect(Initiator& pc, Responder& robot, std::chrono::nanoseconds now) {
  const Handshake w = welcome_for(robot, hello_at(pc, now), now);
  StatePayload state{};
  REQUIRE(pc.open(w, state, now) == SecureStatus::welcome);
  REQUIRE(pc.established());
  SetpointPayload got{};
  REQUIRE(robot.open(next_setpoint(pc), got, now) == SecureStatus::ok);
  REQUIRE(pc.open(answer(robot), state, now) == SecureStatus::ok);
}

}  // namespace

TEST_CASE("SecureSession: nothing is sealed or answered before a handshake, then setpoints obey") {
  Initiator pc(test_key(), console_config());
  Responder robot(test_key(), robot_config());
  SetpointPacket sp{};
  CHECK(pc.seal(setpoint_payload(0x0F), sp) == SecureStatus::no_session);
  StatePacket st{};
  CHECK(robot.seal(state_payload(1), st) == SecureStatus::no_session);
  // A setpoint from another console's session: nothing to check it against, nothing answered.
  Initiator other(test_key(), console_config());
  Responder other_robot(test_key(), robot_config());
  connect(other, other_robot, 1ms);
  SetpointPayload got{};
  got.fill(std::byte{0xEE});
  CHECK(robot.open(next_setpoint(other), got, 1ms) == SecureStatus::no_session);
  CHECK(got[0] == std::byte{0xEE});
  CHECK(robot.take_reply().empty());

  const Handshake hello = hello_at(pc, 2ms);
  const Handshake welcome = welcome_for(robot, hello, 2ms);
  CHECK(welcome.size() == hello.size());  // no amplification
  StatePayload state{};
  REQUIRE(pc.open(welcome, state, 3ms) == SecureStatus::welcome);
  CHECK(pc.granted_round_trip() == 200ms);
  REQUIRE(robot.open(next_setpoint(pc, 0x0F), got, 4ms) == SecureStatus::ok);
  CHECK(got.back() == std::byte{0x0F});  // obeyed: the session is fresh
  CHECK(robot.bound());
  CHECK(robot.peer_session() == pc.session());
  REQUIRE(pc.open(answer(robot, 9), state, 5ms) == SecureStatus::ok);
  CHECK(state == state_payload(9));
  CHECK(pc.peer_session() == robot.session());
}

TEST_CASE("SecureSession: the HELLO is resent until answered, the same WELCOME comes back") {
  Initiator pc(test_key(), console_config());
  Responder robot(test_key(), robot_config());
  Handshake h{};
  const Handshake first = hello_at(pc, 0ms);
  CHECK_FALSE(pc.hello_due(5ms, h));  // hello_interval 10 ms
  const Handshake again = hello_at(pc, 10ms);
  CHECK(again == first);  // the same attempt: same nonce, same timestamp
  const Handshake w1 = welcome_for(robot, first, 10ms);
  SetpointPayload got{};
  // A copy within min_welcome_gap is taken but not answered; later it is, with the same bytes.
  REQUIRE(robot.open(again, got, 12ms) == SecureStatus::hello);
  CHECK(robot.take_reply().empty());
  const Handshake w2 = welcome_for(robot, again, 20ms);
  CHECK(w2 == w1);
  // Resends are bounded: at most max_welcome_resends, and none once the session could no longer
  // open (twice the granted round trip after the first WELCOME).
  int resent = 0;
  for (int i = 0; i < 20; ++i) {
    const auto t = 30ms + i * 10ms;
    if (robot.open(again, got, t) == SecureStatus::hello && !robot.take_reply().empty()) ++resent;
  }
  CHECK(resent == Responder::max_welcome_resends - 1);
  CHECK(robot.open(again, got, 411ms) == SecureStatus::replayed);
  StatePayload state{};
  REQUIRE(pc.open(w2, state, 21ms) == SecureStatus::welcome);
  CHECK(pc.open(w1, state, 21ms) == SecureStatus::replayed);  // the duplicate WELCOME
  CHECK_FALSE(pc.hello_due(40ms, h));                         // a session: no more HELLOs
}

TEST_CASE("SecureSession: duplicates and replays are refused on both sides") {
  Initiator pc(test_key(), console_config());
  Responder robot(test_key(), robot_config());
  connect(pc, robot, 1ms);
  const SetpointPacket sp = next_setpoint(pc);
  SetpointPayload got{};
  REQUIRE(robot.open(sp, got, 2ms) == SecureStatus::ok);
  const StatePacket st = answer(robot);
  StatePayload state{};
  REQUIRE(pc.open(st, state, 2ms) == SecureStatus::ok);
  CHECK(robot.open(sp, got, 3ms) == SecureStatus::replayed);
  CHECK(pc.open(st, state, 3ms) == SecureStatus::replayed);
}

TEST_CASE("SecureSession: commands strictly in order: an older setpoint is never obeyed") {
  Initiator pc(test_key(), console_config());
  Responder robot(test_key(), robot_config());
  connect(pc, robot, 1ms);
  std::vector<SetpointPacket> sent;
  for (int i = 0; i < 70; ++i) sent.push_back(next_setpoint(pc));
  SetpointPayload got{};
  REQUIRE(robot.open(sent[5], got, 2ms) == SecureStatus::ok);
  // A setpoint held back up to 63 packets was obeyed after newer ones before (the tool sent back
  // by up to 0.25 rad in one tick at the 4 rad/s limit). Older than the newest obeyed: refused.
  CHECK(robot.open(sent[3], got, 2ms) == SecureStatus::too_old);
  CHECK(robot.open(sent[4], got, 2ms) == SecureStatus::too_old);
  CHECK(robot.open(sent[5], got, 2ms) == SecureStatus::replayed);
  REQUIRE(robot.open(sent[6], got, 2ms) == SecureStatus::ok);
  REQUIRE(robot.open(sent[69], got, 2ms) == SecureStatus::ok);  // a gap forward is fine
  CHECK(robot.open(sent[68], got, 2ms) == SecureStatus::too_old);
  CHECK(robot.open(sent[0], got, 2ms) == SecureStatus::too_old);
  CHECK(robot.open(sent[69], got, 2ms) == SecureStatus::replayed);
}

TEST_CASE("SecureSession: a setpoint held back past the granted round trip is never obeyed") {
  Initiator pc(test_key(), console_config());
  Responder robot(test_key(), robot_config("rig-a", 50ms));
  connect(pc, robot, 0ms);  // state 1 answered a setpoint received at 0 ms
  // The attacker holds this setpoint (it acknowledges state 1) and drops everything after it.
  const SetpointPacket held = next_setpoint(pc, 0x0F);
  SetpointPayload got{};
  got.fill(std::byte{0xEE});
  CHECK(robot.open(held, got, 51ms) == SecureStatus::stale_answer);
  CHECK(got[0] == std::byte{0xEE});
  // Within the bound it would have been obeyed (a fresh copy of the same situation).
  Initiator pc2(test_key(), console_config());
  Responder robot2(test_key(), robot_config("rig-a", 50ms));
  connect(pc2, robot2, 0ms);
  CHECK(robot2.open(next_setpoint(pc2, 0x0F), got, 50ms) == SecureStatus::ok);
}

TEST_CASE("SecureSession: the console refuses answers to older setpoints unless allowed") {
  Initiator pc(test_key(), console_config());
  Responder robot(test_key(), robot_config());
  connect(pc, robot, 1ms);
  SetpointPayload got{};
  REQUIRE(robot.open(next_setpoint(pc), got, 2ms) == SecureStatus::ok);
  const StatePacket late = answer(robot);
  (void)next_setpoint(pc);  // the console moved on
  StatePayload state{};
  CHECK(pc.open(late, state, 2ms) == SecureStatus::stale_answer);

  Initiator tolerant(test_key(), console_config("rig-a", 1));
  Responder robot2(test_key(), robot_config());
  connect(tolerant, robot2, 1ms);
  REQUIRE(robot2.open(next_setpoint(tolerant), got, 2ms) == SecureStatus::ok);
  const StatePacket late2 = answer(robot2);
  (void)next_setpoint(tolerant);
  CHECK(tolerant.open(late2, state, 2ms) == SecureStatus::ok);
}

TEST_CASE("SecureSession: recorded traffic never moves the robot: after expiry, across restarts") {
  Initiator pc(test_key(), console_config());
  Responder robot(test_key(), robot_config());
  // Record a whole session: its HELLO and 2000 setpoints (the relay of the review).
  const Handshake hello = hello_at(pc, 0ms);
  StatePayload state{};
  REQUIRE(pc.open(welcome_for(robot, hello, 0ms), state, 0ms) == SecureStatus::welcome);
  std::vector<SetpointPacket> recorded;
  SetpointPayload got{};
  for (int i = 0; i < 2000; ++i) {
    recorded.push_back(next_setpoint(pc, 0x0F));
    if (i < 10) {
      REQUIRE(robot.open(recorded.back(), got, 1ms) == SecureStatus::ok);
      REQUIRE(pc.open(answer(robot), state, 1ms) == SecureStatus::ok);
    }
  }
  // The console stops; 200 ms later the session has expired. Replay everything, twice.
  int obeyed = 0, answered = 0;
  for (int round = 0; round < 2; ++round) {
    if (robot.open(hello, got, 200ms) == SecureStatus::hello) ++obeyed;
    if (!robot.take_reply().empty()) ++answered;
    for (const auto& p : recorded) obeyed += robot.open(p, got, 201ms) == SecureStatus::ok;
  }
  CHECK(obeyed == 0);
  CHECK(answered == 0);
  CHECK_FALSE(robot.live_at(201ms));
  // The robot side restarts: it answers the recorded HELLO (it remembers no timestamp), but with
  // a fresh nonce, so the recorded setpoints do not verify under the new session's keys.
  Responder restarted(test_key(), robot_config());
  REQUIRE(restarted.open(hello, got, 300ms) == SecureStatus::hello);
  REQUIRE_FALSE(restarted.take_reply().empty());
  for (const auto& p : recorded) {
    got.fill(std::byte{0xEE});
    CHECK(restarted.open(p, got, 301ms) == SecureStatus::forged);
  }
  CHECK(got[0] == std::byte{0xEE});
  CHECK_FALSE(restarted.bound());
}

TEST_CASE("SecureSession: a console restart takes over at once, the old console is refused") {
  Initiator first(test_key(), console_config());
  Responder robot(test_key(), robot_config());
  connect(first, robot, 1ms);
  const SetpointPacket old_setpoint = next_setpoint(first);
  Initiator second(test_key(), console_config());  // the bridge restarted (a new process)
  const Handshake w = welcome_for(robot, hello_at(second, 2ms), 2ms);
  // Until the new console's first setpoint, the session goes on.
  SetpointPayload got{};
  REQUIRE(robot.open(old_setpoint, got, 2ms) == SecureStatus::ok);
  StatePayload state{};
  REQUIRE(second.open(w, state, 3ms) == SecureStatus::welcome);
  REQUIRE(robot.open(next_setpoint(second), got, 4ms) == SecureStatus::ok);
  CHECK(robot.peer_session() == second.session());
  CHECK(robot.sessions() == 2);
  CHECK(robot.open(next_setpoint(first), got, 5ms) == SecureStatus::forged);
}

TEST_CASE("SecureSession: after a robot restart the console shakes hands again on silence") {
  Initiator pc(test_key(), console_config());
  Responder robot(test_key(), robot_config());
  connect(pc, robot, 0ms);
  Responder restarted(test_key(), robot_config());
  SetpointPayload got{};
  CHECK(restarted.open(next_setpoint(pc), got, 10ms) == SecureStatus::no_session);
  Handshake h{};
  CHECK_FALSE(pc.hello_due(50ms, h));
  CHECK(pc.rehandshake_after() == 400ms);  // twice the granted 200 ms
  const Handshake hello = hello_at(pc, 401ms);
  StatePayload state{};
  REQUIRE(pc.open(welcome_for(restarted, hello, 401ms), state, 402ms) == SecureStatus::welcome);
  REQUIRE(restarted.open(next_setpoint(pc), got, 403ms) == SecureStatus::ok);
  CHECK(pc.sessions() == 2);
}

TEST_CASE("SecureSession: rekeying after rekey_after is seamless: no state is lost") {
  InitiatorConfig cfg = console_config();
  cfg.rekey_after = 1s;
  Initiator pc(test_key(), cfg);
  Responder robot(test_key(), robot_config());
  connect(pc, robot, 0ms);
  SetpointPayload got{};
  StatePayload state{};
  Handshake h{};
  for (auto now = 10ms; now <= 1000ms; now += 10ms) {  // exchanges every 10 ms: no HELLO due
    REQUIRE_FALSE(pc.hello_due(now, h));
    REQUIRE(robot.open(next_setpoint(pc), got, now) == SecureStatus::ok);
    REQUIRE(pc.open(answer(robot), state, now) == SecureStatus::ok);
  }
  const auto t = 1001ms;
  const Handshake hello = hello_at(pc, t);  // the session is 1 s old: a new handshake
  // Setpoints go on in the old session while the handshake runs.
  REQUIRE(robot.open(next_setpoint(pc), got, t) == SecureStatus::ok);
  const StatePacket in_flight = answer(robot, 5);
  const Handshake w = welcome_for(robot, hello, t);
  REQUIRE(pc.open(w, state, t) == SecureStatus::welcome);
  // The old session's answer arrives after the switch: still taken.
  REQUIRE(pc.open(in_flight, state, t) == SecureStatus::ok);
  CHECK(state == state_payload(5));
  REQUIRE(robot.open(next_setpoint(pc), got, t) == SecureStatus::ok);
  REQUIRE(pc.open(answer(robot, 6), state, t) == SecureStatus::ok);
  CHECK(robot.sessions() == 2);
  CHECK(pc.sessions() == 2);
  // Once the new session answered, the old one's states are refused.
  CHECK(pc.open(in_flight, state, t) == SecureStatus::forged);
}

TEST_CASE("SecureSession: another rig, another key, a revoked key: no session") {
  Initiator for_rig_a(test_key(), console_config("rig-a"));
  Responder rig_b(test_key(), robot_config("rig-b"));
  SetpointPayload got{};
  CHECK(rig_b.open(hello_at(for_rig_a, 0ms), got, 0ms) == SecureStatus::wrong_rig);
  CHECK(rig_b.take_reply().empty());

  // Cross-rig splice of data packets: two rigs share a key; console A's setpoints never verify at
  // robot B, B's states never at console A.
  Initiator console_b(test_key(), console_config("rig-b"));
  connect(console_b, rig_b, 20ms);
  Responder rig_a(test_key(), robot_config("rig-a"));
  connect(for_rig_a, rig_a, 20ms);
  CHECK(rig_b.open(next_setpoint(for_rig_a), got, 21ms) == SecureStatus::forged);
  StatePayload state{};
  CHECK(for_rig_a.open(answer(rig_b), state, 21ms) == SecureStatus::forged);

  Initiator other_key(test_key(99), console_config("rig-a"));
  CHECK(rig_a.open(hello_at(other_key, 22ms), got, 22ms) == SecureStatus::wrong_key);

  // Rotation: the robot holds the old key and its successor; consoles with either connect.
  const SecureKey old_key = test_key(1);
  const SecureKey new_key = test_key(2);
  KeyRing ring(old_key);
  ring.add(new_key);
  Responder rotating(ring, robot_config());
  Initiator old_console(old_key, console_config());
  connect(old_console, rotating, 10ms);
  Initiator new_console(new_key, console_config());
  connect(new_console, rotating, 11ms);
  // Revoking the old key ends what runs under it and refuses its HELLOs.
  Initiator old_console2(old_key, console_config());
  connect(old_console2, rotating, 12ms);
  CHECK(rotating.revoke(old_key.id()));
  CHECK_FALSE(rotating.bound());
  CHECK(rotating.open(next_setpoint(old_console2), got, 13ms) == SecureStatus::no_session);
  Initiator old_again(old_key, console_config());
  CHECK(rotating.open(hello_at(old_again, 14ms), got, 14ms) == SecureStatus::wrong_key);
  Initiator new_console2(new_key, console_config());
  connect(new_console2, rotating, 15ms);
  CHECK_THROWS_WITH_AS(ring.add(test_key(3)), doctest::Contains("at most 2"), endohaptics::Error);
  CHECK_THROWS_WITH_AS(KeyRing(old_key).add(old_key), doctest::Contains("there already"),
                       endohaptics::Error);
}

TEST_CASE("SecureSession: the granted round trip is the smaller of asked and allowed") {
  InitiatorConfig cfg = console_config();
  cfg.max_round_trip = 500ms;
  Initiator pc(test_key(), cfg);
  Responder robot(test_key(), robot_config("rig-a", 150ms));
  connect(pc, robot, 0ms);
  CHECK(pc.granted_round_trip() == 150ms);
  CHECK(robot.granted_round_trip() == 150ms);
  // A WELCOME is good for twice the round trip: the first setpoint after that opens nothing.
  Initiator late(test_key(), console_config());
  Responder robot2(test_key(), robot_config("rig-a", 100ms));
  StatePayload state{};
  REQUIRE(late.open(welcome_for(robot2, hello_at(late, 0ms), 0ms), state, 0ms) ==
          SecureStatus::welcome);
  SetpointPayload got{};
  CHECK(robot2.open(next_setpoint(late), got, 201ms) == SecureStatus::no_session);
}

TEST_CASE("SecureSession: a refused packet leaves the session and the caller's buffer untouched") {
  Initiator pc(test_key(), console_config());
  Responder robot(test_key(), robot_config());
  connect(pc, robot, 1ms);
  SetpointPacket sp = next_setpoint(pc);
  sp[40] ^= std::byte{4};
  const auto window = robot.window();
  const auto session = robot.session();
  SetpointPayload got{};
  got.fill(std::byte{0x5A});
  const auto before = got;
  CHECK(robot.open(sp, got, 2ms) == SecureStatus::forged);
  CHECK(robot.open(std::span(sp).first(66), got, 2ms) == SecureStatus::wrong_size);
  CHECK(got == before);
  CHECK(robot.window() == window);
  CHECK(robot.session() == session);
  CHECK(robot.bound());
  // A HELLO with one bit flipped: forged, no answer, nothing pending.
  Initiator other(test_key(), console_config());
  Handshake hello = hello_at(other, 3ms);
  hello[40] ^= std::byte{1};
  CHECK(robot.open(hello, got, 3ms) == SecureStatus::forged);
  CHECK(robot.take_reply().empty());
  CHECK(got == before);
}

TEST_CASE("SecureSession: configuration errors throw") {
  InitiatorConfig c = console_config();
  c.max_round_trip = 0ms;
  CHECK_THROWS_WITH_AS(Initiator(test_key(), c), doctest::Contains("max_round_trip"),
                       endohaptics::Error);
  c = console_config();
  c.max_answer_lag = endohaptics::protocol::packet_history;
  CHECK_THROWS_WITH_AS(Initiator(test_key(), c), doctest::Contains("max_answer_lag"),
                       endohaptics::Error);
  ResponderConfig r = robot_config();
  r.expiry = 0ms;
  CHECK_THROWS_WITH_AS(Responder(test_key(), r), doctest::Contains("expiry"), endohaptics::Error);
  r = robot_config();
  r.max_round_trip = 61s;
  CHECK_THROWS_AS(Responder(test_key(), r), endohaptics::Error);
  CHECK_THROWS_WITH_AS(Responder(KeyRing{}, robot_config()), doctest::Contains("no key"),
                       endohaptics::Error);
  CHECK_THROWS_WITH_AS((void)make_rig_id(""), doctest::Contains("1 to 16"), endohaptics::Error);
  CHECK_THROWS_WITH_AS((void)make_rig_id("seventeen-chars-x"), doctest::Contains("1 to 16"),
                       endohaptics::Error);
  CHECK_THROWS_WITH_AS((void)make_rig_id("a b"), doctest::Contains("printable"),
                       endohaptics::Error);
}

TEST_CASE("SecureSession: exchanges and handshakes allocate nothing") {
  InitiatorConfig cfg = console_config();
  cfg.rekey_after = 1s;
  Initiator pc(test_key(), cfg);
  Responder robot(test_key(), robot_config());
  connect(pc, robot, 0ms);
  const long allocations = endohaptics::test::allocations_during([&] {
    SetpointPacket sp{};
    StatePacket st{};
    SetpointPayload got{};
    StatePayload state{};
    Handshake h{};
    for (int i = 1; i <= 3000; ++i) {
      const auto now = std::chrono::milliseconds(i);
      if (pc.hello_due(now, h)) {  // a rekey every second, inside the loop
        REQUIRE(robot.open(h, got, now) == SecureStatus::hello);
        const auto reply = robot.take_reply();
        REQUIRE(pc.open(reply, state, now) == SecureStatus::welcome);
      }
      REQUIRE(pc.seal(setpoint_payload(0x0F), sp) == SecureStatus::ok);
      REQUIRE(robot.open(sp, got, now) == SecureStatus::ok);
      REQUIRE(robot.seal(state_payload(1), st) == SecureStatus::ok);
      REQUIRE(pc.open(st, state, now) == SecureStatus::ok);
      REQUIRE(pc.open(st, state, now) == SecureStatus::replayed);
    }
  });
  CHECK(allocations == 0);
  CHECK(pc.sessions() == 3);
}

}  // namespace protocol_secure_session_test
