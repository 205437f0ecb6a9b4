#include "endohaptics/transport/v2_gateway.hpp"

#include <doctest/doctest.h>

#include <algorithm>
#include <array>
#include <chrono>
#include <cmath>
#include <cstdint>
#include <limits>
#include <vector>

#include "alloc_counter.hpp"
#include "endohaptics/protocol/packet_codec.hpp"
#include "endohaptics/protocol/secure_session.hpp"
#include "endohaptics/teleop/safety.hpp"
#include "endohaptics/transport/in_memory_transport.hpp"
#include "endohaptics/transport/secure_transport.hpp"

namespace transport_v2_gateway_test {

namespace {

using namespace std::chrono_literals;
namespace protocol = endohaptics::protocol;
namespace transport = endohaptics::transport;
using transport::TransportStatus;
using Link = transport::InMemoryLink<128, 16>;
using Endpoint = Link::Endpoint;
using Console = transport::SecureTransport<Endpoint, protocol::SecureInitiator<4>>;
using RobotSide = transport::SecureTransport<Endpoint, protocol::SecureResponder<4>>;
using Legacy = protocol::PacketCodec<4>;

protocol::SecureKey key(std::uint8_t seed = 1) {
  std::array<std::byte, protocol::SecureKey::size> k{};
  for (std::size_t i = 0; i < k.size(); ++i) k[i] = std::byte{static_cast<std::uint8_t>(seed * i)};
  return protocol::SecureKey(k);
}

Legacy::SetpointBytes setpoint_bytes(std::uint8_t mask, double position = 0.5) {
  Legacy::Setpoint s;
  s.position << position, -position, 0.25, 0.125;
  s.enable_mask = mask;
  Legacy::SetpointBytes b{};
  REQUIRE(Legacy::encode_setpoint(s, b) == protocol::CodecStatus::ok);
  return b;
}

// The 2016 sbRIO on the other end of the point-to-point link: records every setpoint it is sent
// and answers each with a state (positions `measured`; active bits = the enable bits), or with
// `junk` bytes, or not at all.
struct FakeSbrio {
  std::vector<Legacy::Setpoint> received;
  Legacy::State::Vector measured{0.4, -0.4, 0.2, 0.1};  // rad
  bool answer = true;
  bool junk = false;
  // A send to the sbRIO that takes this long on `clock` (a slow host); none without a clock.
  endohaptics::ManualClock* clock = nullptr;
  std::chrono::nanoseconds send_takes{0};
  bool follow = false;  // a tool that is where it was sent at once: measured = the setpoint
};
struct SbrioResponder {
  FakeSbrio* sbrio;
  template <typename Reply>
  void operator()(std::span<const std::byte> datagram, Reply& reply) noexcept {
    Legacy::Setpoint s;
    if (Legacy::decode_setpoint(datagram, s) != protocol::CodecStatus::ok) return;
    if (sbrio->clock != nullptr) sbrio->clock->advance(sbrio->send_takes);
    if (sbrio->follow) sbrio->measured = s.position;
    sbrio->received.push_back(s);  // the test's own bookkeeping (reserved: no allocation)
    if (!sbrio->answer) return;
    if (sbrio->junk) {
      const std::array<std::byte, 20> junk{};
      (void)reply.send(junk);
      return;
    }
    Legacy::State state;
    state.position = sbrio->measured;
    state.active_mask = s.enable_mask;
    Legacy::StateBytes bytes{};
    (void)Legacy::encode_state(state, bytes);
    (void)reply.send(bytes);
  }
};
using SbrioLink = transport::RespondingTransport<SbrioResponder, 128, 16>;
using Gateway = transport::V2Gateway<RobotSide, SbrioLink, endohaptics::ManualClock>;

protocol::InitiatorConfig console_config() {
  protocol::InitiatorConfig c;
  c.rig = protocol::make_rig_id("bench");
  return c;
}

protocol::ResponderConfig robot_config() {
  protocol::ResponderConfig c;
  c.rig = protocol::make_rig_id("bench");
  c.expiry = std::chrono::seconds(60);
  return c;
}

// The gateway's envelope wide open (almost the whole circle, 1000 rad/s): for the tests of
// relaying; the envelope's own tests take the defaults.
transport::GatewayConfig open_envelope() {
  transport::GatewayConfig c;
  c.joint_range = 3.14;
  c.max_setpoint_rate = 1000.0;
  return c;
}

struct Rig {
  FakeSbrio sbrio;
  Link network;
  endohaptics::ManualClock clock{std::chrono::seconds(1)};
  Console console{network.a(), protocol::SecureInitiator<4>(key(), console_config())};
  RobotSide robot{network.b(), protocol::SecureResponder<4>(key(), robot_config())};
  SbrioLink link{SbrioResponder{&sbrio}};
  Gateway gateway;

  explicit Rig(const transport::GatewayConfig& config = open_envelope())
      : gateway(robot, link, clock, config) {
    sbrio.received.reserve(20000);
  }

  // The handshake: the console's first send is the HELLO, the gateway's step answers it.
  void connect() {
    REQUIRE(console.send(setpoint_bytes(0x0F)) == TransportStatus::ok);
    (void)gateway.step(0ns);
    std::array<std::byte, Legacy::state_packet_size + 1> back{};
    REQUIRE(console.receive(back, 0ns).status == TransportStatus::timeout);
    REQUIRE(console.session().established());
  }

  // One setpoint from the console; true when its sealed answer came back.
  bool exchange(std::uint8_t mask, double position = 0.5) {
    REQUIRE(console.send(setpoint_bytes(mask, position)) == TransportStatus::ok);
    (void)gateway.step(0ns);
    std::array<std::byte, Legacy::state_packet_size + 1> back{};
    return console.receive(back, 0ns).status == TransportStatus::ok;
  }

  // Setpoints the sbRIO received with any motor enabled.
  [[nodiscard]] std::size_t enabled_received() const {
    std::size_t n = 0;
    for (const auto& s : sbrio.received) n += s.enable_mask != 0 ? 1 : 0;
    return n;
  }
};

}  // namespace

TEST_CASE("V2Gateway: authentic setpoints reach the sbRIO, its answers return sealed") {
  Rig rig;
  rig.connect();
  rig.sbrio.received.clear();
  CHECK(rig.exchange(0x0F));
  REQUIRE(rig.sbrio.received.size() == 1);
  CHECK(rig.sbrio.received[0].enable_mask == 0x0F);
  CHECK(rig.sbrio.received[0].position[0] == doctest::Approx(0.5));
  for (int i = 0; i < 50; ++i) {
    rig.clock.advance(1ms);
    CHECK(rig.exchange(0x05, 0.25));
  }
  CHECK(rig.sbrio.received.back().enable_mask == 0x05);
  const auto& c = rig.gateway.counters();
  CHECK(c.relayed == 51);
  CHECK(c.returned == 51);
  CHECK(c.unanswered == 0);
  CHECK(c.watchdog_trips == 0);
  CHECK(rig.robot.counters().accepted == 51);
  CHECK(rig.console.counters().accepted == 51);
  CHECK(rig.enabled_received() == 51);
}

TEST_CASE("V2Gateway: 2016 packets, forgeries and replays from the network never reach the sbRIO") {
  Rig rig;
  rig.connect();
  REQUIRE(rig.exchange(0x0F));
  // Capture a valid v2 setpoint on the wire, deliver it once.
  REQUIRE(rig.console.send(setpoint_bytes(0x0F)) == TransportStatus::ok);
  std::array<std::byte, 128> wire{};
  std::size_t size = 0;
  bool truncated = false;
  REQUIRE(rig.network.a_to_b().pop(wire, size, truncated));
  REQUIRE(size == 67);
  const auto valid = std::span<const std::byte>(wire.data(), size);
  rig.network.a_to_b().push(valid);
  (void)rig.gateway.step(0ns);
  REQUIRE(rig.gateway.counters().relayed == 2);
  const auto enabled_before = rig.enabled_received();

  rig.network.a_to_b().push(valid);                 // replayed
  rig.network.a_to_b().push(setpoint_bytes(0x0F));  // a plain 2016 setpoint: 17 bytes
  std::array<std::byte, 67> forged{};
  std::copy(valid.begin(), valid.end(), forged.begin());
  forged[30] ^= std::byte{0x01};
  rig.network.a_to_b().push(forged);  // one bit flipped
  (void)rig.gateway.step(0ns);
  CHECK(rig.robot.counters().replayed == 1);
  CHECK(rig.robot.counters().wrong_size == 1);
  CHECK(rig.robot.counters().forged == 1);
  CHECK(rig.gateway.counters().relayed == 2);
  CHECK(rig.enabled_received() == enabled_before);

  // Nothing but attacks for the watchdog time: the gateway disables the motors itself.
  for (int i = 0; i < 150; ++i) {
    rig.clock.advance(1ms);
    rig.network.a_to_b().push(valid);
    rig.network.a_to_b().push(forged);
    (void)rig.gateway.step(0ns);
  }
  CHECK(rig.gateway.counters().relayed == 2);
  CHECK(rig.enabled_received() == enabled_before);
  CHECK(rig.gateway.counters().watchdog_trips == 1);
  CHECK(rig.gateway.counters().disabled >= 49);
  CHECK(rig.sbrio.received.back().enable_mask == 0);
}

TEST_CASE("V2Gateway: silence sends the disabled setpoint once a period, held where measured") {
  Rig rig;
  // Silent from the start: disabled setpoints at once, positions zero (nothing measured yet).
  (void)rig.gateway.step(0ns);
  REQUIRE(rig.sbrio.received.size() == 1);
  CHECK(rig.sbrio.received[0].enable_mask == 0);
  CHECK(rig.sbrio.received[0].position.isZero());
  (void)rig.gateway.step(0ns);  // not due again within the period
  CHECK(rig.sbrio.received.size() == 1);

  rig.connect();
  rig.sbrio.received.clear();
  REQUIRE(rig.exchange(0x0F));
  CHECK_FALSE(rig.gateway.silent());
  // The watchdog (100 ms) runs out: from then on one disabled setpoint per 1 ms period, at the
  // positions the sbRIO measured last (0.4, -0.4, 0.2, 0.1 rad), not the commanded ones.
  rig.clock.advance(99ms);
  (void)rig.gateway.step(0ns);
  CHECK(rig.sbrio.received.size() == 1);
  rig.clock.advance(1ms);
  const auto step = rig.gateway.step(0ns);
  CHECK(step.disabled);
  CHECK(rig.gateway.silent());
  for (int i = 0; i < 9; ++i) {
    rig.clock.advance(1ms);
    (void)rig.gateway.step(0ns);
  }
  CHECK(rig.gateway.counters().disabled == 11);  // 1 at the start, 10 after the watchdog
  CHECK(rig.gateway.counters().watchdog_trips == 1);
  REQUIRE(rig.sbrio.received.size() == 11);
  for (std::size_t i = 1; i < rig.sbrio.received.size(); ++i) {
    CHECK(rig.sbrio.received[i].enable_mask == 0);
    CHECK(rig.sbrio.received[i].position[0] == doctest::Approx(0.4));
    CHECK(rig.sbrio.received[i].position[3] == doctest::Approx(0.1));
  }
  // A late step sends one, not a burst.
  rig.clock.advance(50ms);
  (void)rig.gateway.step(0ns);
  CHECK(rig.gateway.counters().disabled == 12);
  // The console is back: obeyed again, and no more disabled setpoints.
  CHECK(rig.exchange(0x0F));
  CHECK_FALSE(rig.gateway.silent());
  CHECK(rig.sbrio.received.back().enable_mask == 0x0F);
  rig.clock.advance(5ms);
  (void)rig.gateway.step(0ns);
  CHECK(rig.gateway.counters().disabled == 12);
}

TEST_CASE("V2Gateway: the sbRIO's junk is refused and counted, a missing answer is given up") {
  Rig rig;
  rig.connect();
  rig.sbrio.junk = true;
  CHECK_FALSE(rig.exchange(0x0F));
  CHECK(rig.gateway.counters().sbrio_refused == 1);
  CHECK(rig.gateway.counters().returned == 0);
  rig.clock.advance(3ms);
  (void)rig.gateway.step(0ns);
  CHECK(rig.gateway.counters().unanswered == 1);
  rig.sbrio.junk = false;
  rig.sbrio.answer = false;
  rig.clock.advance(1ms);
  (void)rig.console.send(setpoint_bytes(0x0F));
  (void)rig.gateway.step(0ns);
  rig.clock.advance(3ms);
  (void)rig.gateway.step(0ns);
  CHECK(rig.gateway.counters().relayed == 2);
  CHECK(rig.gateway.counters().unanswered == 2);
  CHECK(rig.gateway.counters().returned == 0);
}

TEST_CASE("V2Gateway: a step allocates nothing") {
  Rig rig;
  rig.connect();
  const auto sp = setpoint_bytes(0x0F);
  const long allocations = endohaptics::test::allocations_during([&] {
    std::array<std::byte, 64> back{};
    for (int i = 0; i < 1000; ++i) {
      rig.clock.advance(1ms);
      REQUIRE(rig.console.send(sp) == TransportStatus::ok);
      REQUIRE(rig.gateway.step(0ns).returned);
      REQUIRE(rig.console.receive(back, 0ns).status == TransportStatus::ok);
    }
    for (int i = 0; i < 200; ++i) {  // silence: disabled setpoints
      rig.clock.advance(1ms);
      (void)rig.gateway.step(0ns);
    }
  });
  CHECK(allocations == 0);
  CHECK(rig.gateway.counters().returned == 1000);
  CHECK(rig.gateway.counters().disabled > 0);
}

TEST_CASE("V2Gateway: relayed setpoints stay in the joint range and the rate limit") {
  // +-1.028 rad, 4 rad/s, a 1 ms period and 10 ms of jitter: each motor's token bucket holds
  // 4 rad/s x 11 ms = 44 mrad (and the wire's 1 urad) and refills 4 mrad per millisecond.
  Rig rig(transport::GatewayConfig{});
  REQUIRE(rig.gateway.config().burst() == doctest::Approx(0.044));
  rig.connect();  // the sbRIO answered the disabled setpoints: 0.4, -0.4, 0.2, 0.1
  rig.sbrio.received.clear();
  // The first setpoint moves one burst at most from where the sbRIO measured the tool.
  CHECK(rig.exchange(0x0F, 0.51));  // 0.51, -0.51, 0.25, 0.125
  REQUIRE(rig.sbrio.received.size() == 1);
  const auto first = rig.sbrio.received[0].position;
  CHECK(first[0] == doctest::Approx(0.444).epsilon(1e-5));
  CHECK(first[1] == doctest::Approx(-0.444).epsilon(1e-5));
  CHECK(first[2] == doctest::Approx(0.244).epsilon(1e-5));
  CHECK(first[3] == doctest::Approx(0.125).epsilon(1e-5));  // 25 mrad: inside the burst
  CHECK(rig.sbrio.received[0].enable_mask == 0x0F);         // the rest of the setpoint untouched
  CHECK(rig.gateway.counters().limited == 1);
  // 1 ms apart, the bucket empty: 4 mrad each, motor 0's 66 mrad reached at the 17th (16 limited).
  for (int i = 0; i < 30; ++i) {
    rig.clock.advance(1ms);
    CHECK(rig.exchange(0x0F, 0.51));
    if (i == 15) CHECK(rig.sbrio.received.back().position[0] == doctest::Approx(0.508));
  }
  CHECK(rig.sbrio.received.back().position[0] == doctest::Approx(0.51).epsilon(1e-5));
  CHECK(rig.sbrio.received.back().position[3] == doctest::Approx(0.125).epsilon(1e-5));
  CHECK(rig.gateway.counters().limited == 17);
  rig.clock.advance(1ms);
  CHECK(rig.exchange(0x0F, 0.51));
  CHECK(rig.gateway.counters().limited == 17);
  // The bucket is full again (13 ms at rest). Three setpoints at once (a burst) move one burst
  // together, not one each.
  for (int i = 0; i < 3; ++i) CHECK(rig.exchange(0x0F, 0.4));
  CHECK(rig.sbrio.received.back().position[0] == doctest::Approx(0.466).epsilon(1e-5));
  // Sending faster buys no speed: 200 setpoints 50 us apart (10 ms) towards -0.5 move 40 mrad,
  // the rate's, after the burst spent above.
  for (int i = 0; i < 200; ++i) {
    rig.clock.advance(50us);
    CHECK(rig.exchange(0x0F, -0.5));
  }
  CHECK(rig.sbrio.received.back().position[0] == doctest::Approx(0.426).epsilon(1e-5));
  // Beyond the range, however slowly: never past 1.028 rad.
  for (int i = 0; i < 400; ++i) {
    rig.clock.advance(1ms);
    (void)rig.exchange(0x0F, 50.0);
    REQUIRE(rig.sbrio.received.back().position.maxCoeff() <= 1.028);
  }
  CHECK(rig.sbrio.received.back().position[0] == doctest::Approx(1.028).epsilon(1e-5));
  // After silence the step is taken from the measured position again, not the last setpoint.
  rig.clock.advance(200ms);
  (void)rig.gateway.step(0ns);  // the disabled setpoint; the sbRIO answers 0.4, -0.4, ...
  REQUIRE(rig.gateway.silent());
  CHECK(rig.exchange(0x0F, -1.0));  // -1, +1, 0.25, 0.125
  CHECK(rig.sbrio.received.back().position[0] == doctest::Approx(0.356).epsilon(1e-5));
  CHECK(rig.sbrio.received.back().position[1] == doctest::Approx(-0.356).epsilon(1e-5));
  // A tool measured outside the range (moved by hand while released, a narrower range than the
  // instrument's) is brought back at the rate, not by a jump to the range's edge.
  rig.sbrio.measured << 1.2, -1.2, 0.2, 0.1;
  rig.clock.advance(200ms);
  (void)rig.gateway.step(0ns);
  CHECK(rig.exchange(0x0F, 0.0));
  CHECK(rig.sbrio.received.back().position[0] == doctest::Approx(1.156).epsilon(1e-5));
  CHECK(rig.sbrio.received.back().position[1] == doctest::Approx(-1.156).epsilon(1e-5));
  rig.clock.advance(1ms);
  CHECK(rig.exchange(0x0F, 2.0));  // further out: held where it is
  CHECK(rig.sbrio.received.back().position[0] == doctest::Approx(1.156).epsilon(1e-5));
}

TEST_CASE("V2Gateway: before the sbRIO answered: the range alone, then the bucket") {
  // Nothing measured yet (the sbRIO does not answer): the first setpoint is kept in the range
  // alone; from then on each enabled motor steps from the last relayed position, its bucket full
  // (44 mrad); a released motor is held at the last relayed position (hold_position()).
  Rig rig(transport::GatewayConfig{});
  rig.sbrio.answer = false;
  rig.connect();
  rig.sbrio.received.clear();
  (void)rig.exchange(0x0F, 0.9);  // 0.9, -0.9, 0.25, 0.125
  REQUIRE(rig.sbrio.received.size() == 1);
  CHECK(rig.sbrio.received[0].position[0] == doctest::Approx(0.9));
  CHECK(rig.gateway.counters().limited == 0);
  rig.clock.advance(1ms);
  (void)rig.exchange(0x0E, -0.95);  // motor 0 released; motor 1 asked to jump 1.85 rad
  const auto& second = rig.sbrio.received.back();
  CHECK(second.position[0] == doctest::Approx(0.9));                         // held
  CHECK(second.position[1] == doctest::Approx(-0.9 + 0.044).epsilon(1e-5));  // one burst
  CHECK(rig.gateway.counters().limited == 1);
  rig.clock.advance(1ms);
  (void)rig.exchange(0x0F, 50.0);  // motor 0 back: from where it was held, a full bucket
  CHECK(rig.sbrio.received.back().position[0] == doctest::Approx(0.944).epsilon(1e-5));
}

TEST_CASE("V2Gateway: releasing a motor between setpoints buys no speed") {
  // A console with the key releases the motors in every other setpoint, so that each next one
  // starts from where the sbRIO measured the tool, and the tool follows at once (measured where
  // it was sent): its bucket is carried through the release, so the tool still moves at the rate
  // plus one burst: from 0.4 rad, 100 setpoints 1 ms apart towards 1 rad end at 0.844 rad at most.
  Rig rig(transport::GatewayConfig{});
  rig.connect();  // the sbRIO answered the disabled setpoints: 0.4, -0.4, 0.2, 0.1
  rig.sbrio.follow = true;
  for (int i = 0; i < 100; ++i) {
    rig.clock.advance(1ms);
    (void)rig.exchange(i % 2 == 0 ? 0x0F : 0x00, 1.0);
  }
  CHECK(rig.sbrio.measured[0] <= 0.4 + 4.0 * 0.1 + rig.gateway.config().burst() + 1e-5);
  CHECK(rig.sbrio.measured[0] > 0.8);  // and no less: the rate is the console's
}

TEST_CASE("V2Gateway: a console within the rate whose setpoints arrive late is never limited") {
  // The bridge's own limit (SetpointRateLimiter, one period's step at most per tick) at the rate,
  // always pushing against it (a target far away, reversed now and then), at 1 kHz with late
  // ticks; the gateway sees each setpoint up to the jitter late (up to 9 ms on the way, at random;
  // a queue: a setpoint sent after a late one waits behind it; and each send to the sbRIO takes
  // 100 us, the setpoints queued meanwhile wait too), and of those that arrive together relays
  // only the newest (the drain): some are never relayed. Before the token bucket, 1759 setpoints
  // relayed after a late one were moved into the envelope; with a bucket that lost each send's
  // time, the bucket emptied while the bridge moved at its rate.
  transport::GatewayConfig config;
  Rig rig(config);
  rig.connect();
  rig.sbrio.clock = &rig.clock;
  rig.sbrio.send_takes = 100us;
  std::uint64_t state = 20261128;
  const auto next = [&state] {
    state = state * 6364136223846793005ULL + 1442695040888963407ULL;
    return static_cast<double>(state >> 11) / 9007199254740992.0;  // [0, 1)
  };
  endohaptics::teleop::SetpointRateLimiter<4> bridge(config.max_setpoint_rate);
  bridge.initialize(rig.sbrio.measured);
  struct InFlight {
    std::chrono::nanoseconds arrives;
    Legacy::SetpointBytes bytes;
  };
  std::vector<InFlight> flight;  // in order: a queue delays, it does not reorder
  flight.reserve(64);
  auto send_time = rig.clock.now();
  auto last_arrival = send_time;
  double target = 0.9;
  std::size_t sent = 0;
  for (int tick = 0; tick < 20000; ++tick) {
    if (next() < 0.002) target = -target;
    const auto gap = std::chrono::microseconds(
        next() < 0.05 ? 1000 + static_cast<int>(next() * 4000) : 1000);  // late ticks
    send_time += gap;
    Legacy::Setpoint s;
    (void)bridge.shape(Legacy::Setpoint::Vector::Constant(target),
                       std::min(std::chrono::duration<double>(gap).count(), 1e-3), s.position);
    s.enable_mask = 0x0F;
    // Up to 9 ms late, never before the one sent before it.
    last_arrival = std::max(last_arrival,
                            send_time + std::chrono::microseconds(static_cast<int>(next() * 9000)));
    InFlight f{last_arrival, {}};
    REQUIRE(Legacy::encode_setpoint(s, f.bytes) == protocol::CodecStatus::ok);
    flight.push_back(f);
    // What arrives before the next tick reaches the gateway, which steps when the next arrives
    // (or at once, still busy with a send): those queued by then it drains, relaying the newest.
    while (!flight.empty() && flight.front().arrives <= send_time + 1ms) {
      if (flight.front().arrives > rig.clock.now()) {
        rig.clock.advance(flight.front().arrives - rig.clock.now());
      }
      const auto now = rig.clock.now();
      while (!flight.empty() && flight.front().arrives <= now) {
        REQUIRE(rig.console.send(flight.front().bytes) == TransportStatus::ok);
        ++sent;
        flight.erase(flight.begin());
      }
      (void)rig.gateway.step(0ns);
      std::array<std::byte, Legacy::state_packet_size + 1> back{};
      (void)rig.console.receive(back, 0ns);
    }
  }
  CHECK(sent > 19000);
  CHECK(rig.gateway.counters().relayed > 5000);
  CHECK(rig.gateway.counters().relayed < sent);  // the drain skipped some
  CHECK(rig.gateway.counters().limited == 0);
}

TEST_CASE("V2Gateway: property: no setpoint sequence leaves the envelope") {
  // Random and hostile setpoints (huge, sign flips, the largest floats, small steps) at random
  // times, bursts among them, with silences and a sbRIO that measures anywhere, also outside the
  // range: every relayed position lies in the range (or, from a tool measured outside it, no
  // further out than the tool); a motor the setpoint releases is sent where the sbRIO measured
  // it; and each motor's path while enabled (each step from the setpoint before, or after
  // silence or a release from where the sbRIO measured it) runs ahead of the rate by at most one
  // burst (and the wire's rounding tolerance, 1 urad) over every stretch of it, on the float
  // wire.
  transport::GatewayConfig config;
  config.joint_range = 0.8;
  config.max_setpoint_rate = 3.0;
  config.jitter = 4ms;
  const double rate = config.max_setpoint_rate;
  const double burst = config.burst();  // 15 mrad
  Rig rig(config);
  rig.connect();
  std::uint64_t state = 20161220;
  const auto next = [&state] {
    state = state * 6364136223846793005ULL + 1442695040888963407ULL;
    return static_cast<double>(state >> 11) / 9007199254740992.0;  // [0, 1)
  };
  const double tolerance = 1e-11;  // double arithmetic on paths of a few hundred rad
  Legacy::Setpoint::Vector previous = Legacy::Setpoint::Vector::Zero();
  bool have_previous = false;
  std::uint8_t previous_mask = 0;
  double outside = rig.sbrio.measured.cwiseAbs().maxCoeff();  // where the tool was measured
  // Per motor: the path relayed (rad, the sum of the steps, each from its reference), and the
  // least of (the path before a step) - rate x (the step's time) so far: the steps of any stretch
  // of relays, its first included, exceed the rate times the stretch's time by one burst at most,
  // through releases and silences too.
  std::array<double, 4> path{};
  std::array<double, 4> least{};
  least.fill(std::numeric_limits<double>::infinity());
  std::uint64_t relayed = rig.gateway.counters().relayed;
  double max_ahead = 0.0;
  for (int i = 0; i < 20000; ++i) {
    if (next() < 0.001) {
      rig.clock.advance(150ms);  // silence: the watchdog trips
      if (next() < 0.5) rig.sbrio.measured.setConstant((next() - 0.5) * 3.0);
      (void)rig.gateway.step(0ns);
      have_previous = false;
      outside = rig.sbrio.measured.cwiseAbs().maxCoeff();
    } else if (next() < 0.2) {
      rig.clock.advance(std::chrono::microseconds(static_cast<int>(next() * 20)));  // a burst
    } else {
      rig.clock.advance(std::chrono::microseconds(static_cast<int>(next() * 3000)));
    }
    Legacy::Setpoint s;
    for (int m = 0; m < 4; ++m) {
      const double kind = next();
      s.position[m] = kind < 0.05  ? 3.0e38 * (next() < 0.5 ? -1 : 1)
                      : kind < 0.5 ? (next() - 0.5) * 20.0
                                   : previous[m] + (next() - 0.5) * 0.02;
    }
    s.enable_mask = static_cast<std::uint8_t>(next() * 16);
    Legacy::SetpointBytes b{};
    REQUIRE(Legacy::encode_setpoint(s, b) == protocol::CodecStatus::ok);
    REQUIRE(rig.console.send(b) == TransportStatus::ok);
    (void)rig.gateway.step(0ns);
    std::array<std::byte, Legacy::state_packet_size + 1> back{};
    (void)rig.console.receive(back, 0ns);
    if (rig.gateway.counters().relayed != relayed) {
      relayed = rig.gateway.counters().relayed;
      const auto& r = rig.sbrio.received.back();
      REQUIRE(r.position.cwiseAbs().maxCoeff() <= std::max(config.joint_range, outside) + 1e-6);
      const double t = std::chrono::duration<double>(rig.clock.now()).count();
      for (std::size_t m = 0; m < 4; ++m) {
        const int j = static_cast<int>(m);
        const double measured = static_cast<float>(rig.sbrio.measured[j]);  // as on the wire
        if (((r.enable_mask >> m) & 1u) == 0) {  // released: held where it was measured
          REQUIRE(r.position[j] == measured);
          continue;
        }
        // From the setpoint before if it enabled the motor, else (after silence, or released
        // before) from where the sbRIO measured it.
        const double ref =
            have_previous && ((previous_mask >> m) & 1u) != 0 ? previous[j] : measured;
        least[m] = std::min(least[m], path[m] - rate * t);
        path[m] += std::abs(r.position[j] - ref);
        const double ahead = path[m] - rate * t - least[m];
        max_ahead = std::max(max_ahead, ahead);
        REQUIRE(ahead <= burst + Gateway::wire_tolerance + tolerance);
      }
      previous = r.position;
      previous_mask = r.enable_mask;
      have_previous = true;
    }
    rig.sbrio.received.clear();
  }
  CHECK(rig.gateway.counters().relayed > 15000);
  CHECK(rig.gateway.counters().limited > 3000);
  CHECK(max_ahead > 0.9 * burst);  // the bound is reached, not just respected from afar
}

TEST_CASE("GatewayConfig: out-of-range timing is refused naming the field") {
  transport::GatewayConfig c;
  CHECK_NOTHROW(c.validate());
  c.watchdog = 0ns;
  CHECK_THROWS_WITH_AS(c.validate(), doctest::Contains("watchdog must be in [1 ms, 10 s]"),
                       endohaptics::Error);
  c = {};
  c.period = 200ms;
  CHECK_THROWS_WITH_AS(c.validate(), doctest::Contains("period"), endohaptics::Error);
  c = {};
  c.watchdog = 5ms;
  c.period = 10ms;
  CHECK_THROWS_WITH_AS(c.validate(), doctest::Contains("must not exceed watchdog"),
                       endohaptics::Error);
  c = {};
  c.watchdog = 5ms;  // shorter than the default jitter: the two are independent
  CHECK_NOTHROW(c.validate());
  c.jitter = 100ms;
  CHECK_NOTHROW(c.validate());
  c.jitter = 101ms;
  CHECK_THROWS_WITH_AS(c.validate(),
                       doctest::Contains("jitter must be in [0, 100] ms, got 101000000 ns"),
                       endohaptics::Error);
  c.jitter = -1ns;
  CHECK_THROWS_WITH_AS(c.validate(), doctest::Contains("jitter must be in"), endohaptics::Error);
  c = {};
  c.answer_timeout = -1ns;
  CHECK_THROWS_WITH_AS(c.validate(), doctest::Contains("answer_timeout"), endohaptics::Error);
}

TEST_CASE("GatewayConfig: an envelope outside the physical range is refused naming the field") {
  for (const double range : {0.0, -1.0, 3.2, std::numeric_limits<double>::quiet_NaN(),
                             std::numeric_limits<double>::infinity()}) {
    transport::GatewayConfig c;
    c.joint_range = range;
    CHECK_THROWS_WITH_AS(c.validate(), doctest::Contains("joint_range must be in (0, pi] rad"),
                         endohaptics::Error);
  }
  for (const double rate : {0.0, 1001.0, std::numeric_limits<double>::quiet_NaN()}) {
    transport::GatewayConfig c;
    c.max_setpoint_rate = rate;
    CHECK_THROWS_WITH_AS(c.validate(),
                         doctest::Contains("max_setpoint_rate must be in (0, 1000] rad/s"),
                         endohaptics::Error);
  }
}

}  // namespace transport_v2_gateway_test
