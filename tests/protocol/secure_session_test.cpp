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

SecureKey test_key(std::uint8_t seed = 7) {
  std::array<std::byte, SecureKey::size> k{};
  for (std::size_t i = 0; i < k.size(); ++i) k[i] = std::byte{static_cast<std::uint8_t>(seed + i)};
  return SecureKey(k);
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

StatePacket answer(Responder& sbrio, std::uint8_t marker = 1) {
  StatePacket out{};
  REQUIRE(sbrio.seal(state_payload(marker), out) == SecureStatus::ok);
  return out;
}

// Runs the handshake: the PC's first setpoint is answered unbound, the second binds.
void handshake(Initiator& pc, Responder& sbrio, std::chrono::nanoseconds now) {
  SetpointPayload got{};
  StatePayload state{};
  REQUIRE(sbrio.open(next_setpoint(pc), got, now) == SecureStatus::unbound);
  REQUIRE(pc.open(answer(sbrio), state) == SecureStatus::ok);
  REQUIRE(sbrio.open(next_setpoint(pc), got, now) == SecureStatus::ok);
  REQUIRE(sbrio.bound());
  REQUIRE(pc.open(answer(sbrio), state) == SecureStatus::ok);
}

}  // namespace

TEST_CASE("SecureSession: handshake: the first setpoint is answered but never obeyed") {
  Initiator pc(test_key(), 0x1111);
  Responder sbrio(test_key(), 0x2222);
  SetpointPayload got{};
  got.fill(std::byte{0xEE});
  REQUIRE(sbrio.open(next_setpoint(pc, 0x0F), got, 1ms) == SecureStatus::unbound);
  CHECK(got.back() == std::byte{0});  // every motor disabled
  CHECK_FALSE(sbrio.bound());
  StatePayload state{};
  REQUIRE(pc.open(answer(sbrio, 9), state) == SecureStatus::ok);
  CHECK(state == state_payload(9));
  CHECK(pc.peer_session() == 0x2222);
  REQUIRE(sbrio.open(next_setpoint(pc, 0x0F), got, 2ms) == SecureStatus::ok);
  CHECK(got.back() == std::byte{0x0F});  // bound: obeyed
  CHECK(sbrio.bound());
  CHECK(sbrio.peer_session() == 0x1111);
  REQUIRE(pc.open(answer(sbrio), state) == SecureStatus::ok);
}

TEST_CASE("SecureSession: duplicates and replays are refused on both sides") {
  Initiator pc(test_key(), 0x1111);
  Responder sbrio(test_key(), 0x2222);
  handshake(pc, sbrio, 1ms);
  const SetpointPacket sp = next_setpoint(pc);
  SetpointPayload got{};
  REQUIRE(sbrio.open(sp, got, 2ms) == SecureStatus::ok);
  const StatePacket st = answer(sbrio);
  StatePayload state{};
  REQUIRE(pc.open(st, state) == SecureStatus::ok);
  CHECK(sbrio.open(sp, got, 3ms) == SecureStatus::replayed);
  CHECK(pc.open(st, state) == SecureStatus::replayed);
}

TEST_CASE("SecureSession: commands strictly in order: an older setpoint is never obeyed") {
  Initiator pc(test_key(), 0x1111);
  Responder sbrio(test_key(), 0x2222);
  handshake(pc, sbrio, 1ms);
  std::vector<SetpointPacket> sent;
  for (int i = 0; i < 70; ++i) sent.push_back(next_setpoint(pc));
  SetpointPayload got{};
  REQUIRE(sbrio.open(sent[5], got, 2ms) == SecureStatus::ok);
  // Before: a setpoint held back up to 63 packets was obeyed after newer ones (the tool sent back
  // by up to 0.25 rad in one tick at the 4 rad/s limit). Now older than the newest obeyed: refused.
  CHECK(sbrio.open(sent[3], got, 2ms) == SecureStatus::too_old);
  CHECK(sbrio.open(sent[4], got, 2ms) == SecureStatus::too_old);
  CHECK(sbrio.open(sent[5], got, 2ms) == SecureStatus::replayed);
  REQUIRE(sbrio.open(sent[6], got, 2ms) == SecureStatus::ok);
  REQUIRE(sbrio.open(sent[69], got, 2ms) == SecureStatus::ok);  // a gap forward is fine
  CHECK(sbrio.open(sent[68], got, 2ms) == SecureStatus::too_old);
  CHECK(sbrio.open(sent[0], got, 2ms) == SecureStatus::too_old);
  CHECK(sbrio.open(sent[69], got, 2ms) == SecureStatus::replayed);
}

TEST_CASE("SecureSession: the PC refuses answers to older setpoints unless allowed") {
  Initiator pc(test_key(), 0x1111);
  Responder sbrio(test_key(), 0x2222);
  handshake(pc, sbrio, 1ms);
  SetpointPayload got{};
  REQUIRE(sbrio.open(next_setpoint(pc), got, 2ms) == SecureStatus::ok);
  const StatePacket late = answer(sbrio);
  (void)next_setpoint(pc);  // the PC moved on
  StatePayload state{};
  CHECK(pc.open(late, state) == SecureStatus::stale_answer);

  Initiator tolerant(test_key(), 0x3333, 1);
  Responder sbrio2(test_key(), 0x4444);
  handshake(tolerant, sbrio2, 1ms);
  REQUIRE(sbrio2.open(next_setpoint(tolerant), got, 2ms) == SecureStatus::ok);
  const StatePacket late2 = answer(sbrio2);
  (void)next_setpoint(tolerant);
  CHECK(tolerant.open(late2, state) == SecureStatus::ok);
}

TEST_CASE("SecureSession: a second PC cannot take over a live session") {
  Initiator pc(test_key(), 0x1111);
  Initiator intruder(test_key(), 0x5555);  // has the key, e.g. a second bridge started by mistake
  Responder sbrio(test_key(), 0x2222);
  handshake(pc, sbrio, 1ms);
  SetpointPayload got{};
  got.fill(std::byte{0xEE});
  const auto before = got;
  CHECK(sbrio.open(next_setpoint(intruder), got, 2ms) == SecureStatus::wrong_session);
  CHECK(got == before);
  CHECK(sbrio.peer_session() == 0x1111);
  REQUIRE(sbrio.open(next_setpoint(pc), got, 3ms) == SecureStatus::ok);
}

TEST_CASE("SecureSession: after expiry nothing of the old session is obeyed again") {
  Initiator pc(test_key(), 0x1111);
  Responder sbrio(test_key(), 0x2222);
  handshake(pc, sbrio, 1ms);
  const SetpointPacket captured = next_setpoint(pc, 0x0F);
  SetpointPayload got{};
  REQUIRE(sbrio.open(captured, got, 2ms) == SecureStatus::ok);
  const std::uint64_t old_session = sbrio.session();
  // 100 ms of silence: the binding expires. A new packet of the old session (or a replay of one
  // never seen) is answered with every motor disabled, under a new session id.
  const SetpointPacket later = next_setpoint(pc, 0x0F);
  REQUIRE(sbrio.open(later, got, 200ms) == SecureStatus::unbound);
  CHECK(got.back() == std::byte{0});
  CHECK_FALSE(sbrio.bound());
  CHECK(sbrio.session() != old_session);
  // The captured packet replayed now: not obeyed.
  REQUIRE(sbrio.open(captured, got, 201ms) == SecureStatus::unbound);
  CHECK(got.back() == std::byte{0});
  // Its answer goes to whoever replayed it; the live PC refuses it (not its newest setpoint).
  StatePayload state{};
  CHECK(pc.open(answer(sbrio), state) == SecureStatus::stale_answer);
  // The live PC rebinds through the new session id.
  REQUIRE(sbrio.open(next_setpoint(pc, 0x0F), got, 202ms) == SecureStatus::unbound);
  REQUIRE(pc.open(answer(sbrio), state) == SecureStatus::ok);
  CHECK(pc.peer_session() == sbrio.session());
  REQUIRE(sbrio.open(next_setpoint(pc, 0x0F), got, 202ms) == SecureStatus::ok);
  CHECK(got.back() == std::byte{0x0F});
  CHECK(sbrio.open(captured, got, 203ms) == SecureStatus::wrong_session);
}

TEST_CASE("SecureSession: the PC follows an sbRIO restart, never back to an earlier session") {
  Initiator pc(test_key(), 0x1111);
  Responder first(test_key(), 0x2222);
  handshake(pc, first, 1ms);
  SetpointPayload got{};
  REQUIRE(first.open(next_setpoint(pc), got, 2ms) == SecureStatus::ok);
  const StatePacket old_state = answer(first);
  // Replaying a state of the current session after a newer one: replayed.
  StatePayload state{};
  REQUIRE(pc.open(old_state, state) == SecureStatus::ok);
  Responder second(test_key(), 0x6666);  // the sbRIO restarted
  REQUIRE(second.open(next_setpoint(pc), got, 1ms) == SecureStatus::unbound);
  REQUIRE(pc.open(answer(second), state) == SecureStatus::ok);
  CHECK(pc.peer_session() == 0x6666);
  CHECK(pc.open(old_state, state) == SecureStatus::wrong_session);
}

TEST_CASE("SecureSession: states for another PC run are refused") {
  Initiator pc(test_key(), 0x1111);
  Initiator other(test_key(), 0x7777);
  Responder sbrio(test_key(), 0x2222);
  SetpointPayload got{};
  REQUIRE(sbrio.open(next_setpoint(other), got, 1ms) == SecureStatus::unbound);
  StatePayload state{};
  (void)next_setpoint(pc);
  CHECK(pc.open(answer(sbrio), state) == SecureStatus::wrong_session);
  CHECK(pc.peer_session() == 0);
}

TEST_CASE("SecureSession: a refused packet leaves the session and the caller's buffer untouched") {
  Initiator pc(test_key(), 0x1111);
  Responder sbrio(test_key(), 0x2222);
  handshake(pc, sbrio, 1ms);
  SetpointPacket sp = next_setpoint(pc);
  sp[40] ^= std::byte{4};
  const auto window = sbrio.window();
  const auto session = sbrio.session();
  SetpointPayload got{};
  got.fill(std::byte{0x5A});
  const auto before = got;
  CHECK(sbrio.open(sp, got, 2ms) == SecureStatus::forged);
  CHECK(sbrio.open(std::span(sp).first(66), got, 2ms) == SecureStatus::wrong_size);
  // A forgery long after the binding would have expired changes nothing either.
  CHECK(sbrio.open(sp, got, 10s) == SecureStatus::forged);
  CHECK(got == before);
  CHECK(sbrio.window() == window);
  CHECK(sbrio.session() == session);
  CHECK(sbrio.bound());

  SecureKey wrong = test_key(99);
  Responder fake(wrong, 0x2222);
  (void)fake.open(next_setpoint(pc), got, 2ms);
  StatePacket st{};
  REQUIRE(fake.seal(state_payload(1), st) == SecureStatus::ok);
  const auto pc_window = pc.window();
  StatePayload state{};
  state.fill(std::byte{0x33});
  const auto state_before = state;
  CHECK(pc.open(st, state) == SecureStatus::forged);
  CHECK(state == state_before);
  CHECK(pc.window() == pc_window);
  CHECK(pc.peer_session() == 0x2222);
}

TEST_CASE("SecureSession: (session, sequence) never repeats: sequences count from 1 per session") {
  Initiator a(test_key(), endohaptics::protocol::random_session_id());
  Initiator b(test_key(), endohaptics::protocol::random_session_id());
  CHECK(a.session() != b.session());
  CHECK(a.session() != 0);
  const SetpointPacket pa = next_setpoint(a);
  const SetpointPacket pb = next_setpoint(b);
  CHECK(pa != pb);  // same payload, same key, different sessions: different packets and tags
  CHECK(a.sent() == 1);
}

TEST_CASE("SecureSession: configuration errors throw") {
  CHECK_THROWS_WITH_AS(Initiator(test_key(), 0), doctest::Contains("non-zero"), endohaptics::Error);
  CHECK_THROWS_WITH_AS(Responder(test_key(), 1, 0ms), doctest::Contains("expiry"),
                       endohaptics::Error);
}

TEST_CASE("SecureSession: exchanges allocate nothing") {
  Initiator pc(test_key(), 0x1111);
  Responder sbrio(test_key(), 0x2222);
  handshake(pc, sbrio, 1ms);
  const long allocations = endohaptics::test::allocations_during([&] {
    SetpointPacket sp{};
    StatePacket st{};
    SetpointPayload got{};
    StatePayload state{};
    for (int i = 0; i < 1000; ++i) {
      REQUIRE(pc.seal(setpoint_payload(0x0F), sp) == SecureStatus::ok);
      REQUIRE(sbrio.open(sp, got, 2ms) == SecureStatus::ok);
      REQUIRE(sbrio.seal(state_payload(1), st) == SecureStatus::ok);
      REQUIRE(pc.open(st, state) == SecureStatus::ok);
      REQUIRE(pc.open(st, state) == SecureStatus::replayed);
    }
  });
  CHECK(allocations == 0);
}

TEST_CASE(
    "SecureSession: a binding setpoint held back by an attacker and delivered later never binds") {
  Initiator pc(test_key(), 0x1111);
  Responder sbrio(test_key(), 0x2222, 100ms);
  SetpointPayload got{};
  StatePayload state{};
  // The PC's first setpoint is answered unbound; its answer reaches the PC.
  REQUIRE(sbrio.open(next_setpoint(pc), got, 1ms) == SecureStatus::unbound);
  REQUIRE(pc.open(answer(sbrio), state) == SecureStatus::ok);
  // The attacker drops the PC's next setpoints (they echo the sbRIO's session, enable mask 15)
  // and delivers them 10 s later, when the PC is long gone.
  std::vector<SetpointPacket> held;
  for (int i = 0; i < 5; ++i) held.push_back(next_setpoint(pc, 0x0F));
  for (const SetpointPacket& p : held) {
    got.fill(std::byte{0xEE});
    CHECK(sbrio.open(p, got, 10s) == SecureStatus::unbound);
    CHECK(got.back() == std::byte{0});  // every motor disabled
    CHECK_FALSE(sbrio.bound());
  }
}

TEST_CASE(
    "SecureSession: a binding setpoint within the expiry of the state it acknowledges binds") {
  Initiator pc(test_key(), 0x1111);
  Responder sbrio(test_key(), 0x2222, 100ms);
  SetpointPayload got{};
  StatePayload state{};
  REQUIRE(sbrio.open(next_setpoint(pc), got, 1ms) == SecureStatus::unbound);
  REQUIRE(pc.open(answer(sbrio), state) == SecureStatus::ok);
  // 99 ms later (a slow link): still within the expiry.
  got.fill(std::byte{0xEE});
  CHECK(sbrio.open(next_setpoint(pc, 0x0F), got, 100ms) == SecureStatus::ok);
  CHECK(sbrio.bound());
  CHECK(got.back() == std::byte{0x0F});
}

TEST_CASE("SecureSession: a round trip beyond the expiry binds within max_round_trip, not after") {
  // The emulator's --delay 105 against a 100 ms watchdog (expiry): the echo takes 106 ms. With
  // max_round_trip 0 (= the expiry) it never binds; with 205 ms it binds; beyond that it does not.
  for (const auto& c : {std::tuple{0ms, 107ms, false}, std::tuple{205ms, 107ms, true},
                        std::tuple{205ms, 207ms, false}}) {
    const auto round_trip = std::get<0>(c);
    const auto arrives = std::get<1>(c);
    const bool binds = std::get<2>(c);
    CAPTURE(round_trip.count());
    CAPTURE(arrives.count());
    Initiator pc(test_key(), 0x1111, 200);
    Responder sbrio(test_key(), 0x2222, 100ms, round_trip);
    SetpointPayload got{};
    StatePayload state{};
    REQUIRE(sbrio.open(next_setpoint(pc), got, 1ms) == SecureStatus::unbound);
    REQUIRE(pc.open(answer(sbrio), state) == SecureStatus::ok);
    CHECK(sbrio.open(next_setpoint(pc, 0x0F), got, arrives) ==
          (binds ? SecureStatus::ok : SecureStatus::unbound));
    CHECK(sbrio.bound() == binds);
    CHECK(got.back() == (binds ? std::byte{0x0F} : std::byte{0}));
  }
  CHECK_THROWS_AS(Responder(test_key(), 0x2222, 100ms, -1ms), endohaptics::Error);
}

}  // namespace protocol_secure_session_test
