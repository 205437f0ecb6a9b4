#include "endohaptics/transport/secure_transport.hpp"

#include <doctest/doctest.h>

#include <array>
#include <chrono>
#include <cstdint>

#include "alloc_counter.hpp"
#include "endohaptics/protocol/packet_codec.hpp"
#include "endohaptics/transport/in_memory_transport.hpp"

namespace protocol_secure_transport_test {

namespace {

using namespace std::chrono_literals;
namespace protocol = endohaptics::protocol;
namespace transport = endohaptics::transport;
using Link = transport::InMemoryLink<128, 16>;
using Endpoint = Link::Endpoint;
using PcSide = transport::SecureTransport<Endpoint, protocol::SecureInitiator<4>>;
using SbrioSide = transport::SecureTransport<Endpoint, protocol::SecureResponder<4>>;
using Legacy = protocol::PacketCodec<4>;

static_assert(transport::FilteringTransport<PcSide>);
static_assert(transport::FilteringTransport<SbrioSide>);

protocol::SecureKey key(std::uint8_t seed = 1) {
  std::array<std::byte, protocol::SecureKey::size> k{};
  for (std::size_t i = 0; i < k.size(); ++i) k[i] = std::byte{static_cast<std::uint8_t>(seed * i)};
  return protocol::SecureKey(k);
}

Legacy::SetpointBytes setpoint_bytes(std::uint8_t mask) {
  Legacy::Setpoint s;
  s.position << 0.5, -0.5, 0.25, 0.125;
  s.enable_mask = mask;
  Legacy::SetpointBytes b{};
  REQUIRE(Legacy::encode_setpoint(s, b) == protocol::CodecStatus::ok);
  return b;
}

Legacy::StateBytes state_bytes() {
  Legacy::State s;
  s.position << 0.5, -0.5, 0.25, 0.125;
  s.active_mask = 0x0F;
  Legacy::StateBytes b{};
  REQUIRE(Legacy::encode_state(s, b) == protocol::CodecStatus::ok);
  return b;
}

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

struct Pair {
  Link link;
  PcSide pc{link.a(), protocol::SecureInitiator<4>(key(), console_config())};
  SbrioSide sbrio{link.b(), protocol::SecureResponder<4>(key(), robot_config())};

  // The handshake through the transports: the first send carries the HELLO only, the robot's
  // receive answers it (silence to its caller), the console's receive takes the WELCOME.
  void connect() {
    REQUIRE(pc.send(setpoint_bytes(0x0F)) == transport::TransportStatus::ok);
    REQUIRE(link.a_to_b().size() == 1);  // the HELLO, no setpoint
    CHECK(pc.held_before_session() == 1);
    std::array<std::byte, Legacy::setpoint_packet_size + 1> in{};
    REQUIRE(sbrio.receive(in, 0ns).status == transport::TransportStatus::timeout);
    REQUIRE(link.b_to_a().size() == 1);  // the WELCOME
    std::array<std::byte, Legacy::state_packet_size + 1> back{};
    REQUIRE(pc.receive(back, 0ns).status == transport::TransportStatus::timeout);
    REQUIRE(pc.session().established());
  }

  // One exchange; returns the mask the sbRIO side delivered.
  std::uint8_t exchange(std::uint8_t mask) {
    REQUIRE(pc.send(setpoint_bytes(mask)) == transport::TransportStatus::ok);
    std::array<std::byte, Legacy::setpoint_packet_size + 1> in{};
    const auto r = sbrio.receive(in, 0ns);
    REQUIRE(r.status == transport::TransportStatus::ok);
    REQUIRE(r.size == Legacy::setpoint_packet_size);
    REQUIRE(sbrio.send(state_bytes()) == transport::TransportStatus::ok);
    std::array<std::byte, Legacy::state_packet_size + 1> back{};
    const auto s = pc.receive(back, 0ns);
    REQUIRE(s.status == transport::TransportStatus::ok);
    REQUIRE(s.size == Legacy::state_packet_size);
    return std::to_integer<std::uint8_t>(in[Legacy::setpoint_packet_size - 1]);
  }
};

}  // namespace

TEST_CASE("SecureTransport: shakes hands, then carries 2016 packets, each obeyed") {
  Pair p;
  p.connect();
  CHECK(p.exchange(0x0F) == 0x0F);
  CHECK(p.exchange(0x05) == 0x05);
  CHECK(p.sbrio.counters().accepted == 2);
  CHECK(p.sbrio.counters().handshakes == 1);
  CHECK(p.pc.counters().handshakes == 1);
  CHECK(p.pc.counters().accepted == 2);
  CHECK(p.pc.counters().rejected() == 0);
  CHECK(p.sbrio.counters().rejected() == 0);
}

TEST_CASE("SecureTransport: the robot side answers nothing but a fresh HELLO") {
  Pair p;
  p.connect();
  (void)p.exchange(0x0F);
  // Record the HELLO and a setpoint; a new robot side (restarted) meets them with a new console
  // silent: the setpoint is not answered, the HELLO's WELCOME opens keys the recording lacks.
  Link other;
  PcSide pc2{other.a(), protocol::SecureInitiator<4>(key(), console_config())};
  REQUIRE(pc2.send(setpoint_bytes(0x0F)) == transport::TransportStatus::ok);
  std::array<std::byte, 128> hello{};
  std::size_t size = 0;
  bool truncated = false;
  REQUIRE(other.a_to_b().pop(hello, size, truncated));
  REQUIRE(size == protocol::HandshakeCodec::packet_size);
  REQUIRE(p.pc.send(setpoint_bytes(0x0F)) == transport::TransportStatus::ok);
  std::array<std::byte, 128> setpoint{};
  std::size_t setpoint_size = 0;
  REQUIRE(p.link.a_to_b().pop(setpoint, setpoint_size, truncated));
  SbrioSide fresh{other.b(), protocol::SecureResponder<4>(key(), robot_config())};
  std::array<std::byte, 32> in{};
  other.a_to_b().push(std::span<const std::byte>(setpoint.data(), setpoint_size));
  CHECK(fresh.receive(in, 0ns).status == transport::TransportStatus::timeout);
  CHECK(fresh.counters().no_session == 1);
  CHECK(other.b_to_a().size() == 0);  // nothing answered, nothing reflected
  other.a_to_b().push(std::span<const std::byte>(hello.data(), size));
  CHECK(fresh.receive(in, 0ns).status == transport::TransportStatus::timeout);
  REQUIRE(other.b_to_a().size() == 1);
  std::array<std::byte, 128> welcome{};
  std::size_t welcome_size = 0;
  REQUIRE(other.b_to_a().pop(welcome, welcome_size, truncated));
  CHECK(welcome_size == size);  // no larger than the request
  // The same HELLO again, and again: no second WELCOME within min_welcome_gap.
  for (int i = 0; i < 10; ++i) other.a_to_b().push(std::span<const std::byte>(hello.data(), size));
  CHECK(fresh.receive(in, 0ns).status == transport::TransportStatus::timeout);
  CHECK(other.b_to_a().size() <= 1);
  other.a_to_b().push(std::span<const std::byte>(setpoint.data(), setpoint_size));
  CHECK(fresh.receive(in, 0ns).status == transport::TransportStatus::timeout);
  CHECK(fresh.counters().accepted == 0);
}

TEST_CASE("SecureTransport: forgeries and replays never reach the filter, all-forged is silence") {
  Pair p;
  p.connect();
  (void)p.exchange(0x0F);
  // Capture a valid setpoint on the wire, deliver it, then replay it and flip bits in copies.
  REQUIRE(p.pc.send(setpoint_bytes(0x0F)) == transport::TransportStatus::ok);
  std::array<std::byte, 128> wire{};
  std::size_t size = 0;
  bool truncated = false;
  REQUIRE(p.link.a_to_b().pop(wire, size, truncated));
  REQUIRE(size == 67);
  const auto valid = std::span<const std::byte>(wire.data(), size);
  p.link.a_to_b().push(valid);
  std::array<std::byte, 32> in{};
  REQUIRE(p.sbrio.receive(in, 0ns).status == transport::TransportStatus::ok);

  int calls = 0;
  auto counting = [&calls](std::span<const std::byte>) noexcept {
    ++calls;
    return true;
  };
  p.link.a_to_b().push(valid);  // replay
  auto r = p.sbrio.receive(in, 0ns, counting);
  CHECK(r.status == transport::TransportStatus::timeout);
  CHECK(p.sbrio.counters().replayed == 1);
  for (int bit = 0; bit < 8 * 67; bit += 67) {
    std::array<std::byte, 67> bad{};
    std::copy(valid.begin(), valid.end(), bad.begin());
    bad[static_cast<std::size_t>(bit / 8)] ^= std::byte{static_cast<std::uint8_t>(1u << (bit % 8))};
    p.link.a_to_b().push(bad);
  }
  r = p.sbrio.receive(in, 0ns, counting);
  CHECK(r.status == transport::TransportStatus::timeout);
  CHECK(p.sbrio.counters().forged == 8);
  p.link.a_to_b().push(valid.first(40));
  r = p.sbrio.receive(in, 0ns, counting);
  CHECK(r.status == transport::TransportStatus::timeout);
  CHECK(p.sbrio.counters().wrong_size == 1);
  CHECK(calls == 0);
}

TEST_CASE("SecureTransport: a valid packet behind forged ones still gets through") {
  Pair p;
  p.connect();
  (void)p.exchange(0x0F);
  REQUIRE(p.pc.send(setpoint_bytes(0x03)) == transport::TransportStatus::ok);
  std::array<std::byte, 67> junk{};
  for (int i = 0; i < 5; ++i) p.link.a_to_b().push(junk);
  std::array<std::byte, 32> in{};
  const auto r = p.sbrio.receive(in, 0ns);
  REQUIRE(r.status == transport::TransportStatus::ok);
  CHECK(std::to_integer<int>(in[16]) == 3);
  CHECK(p.sbrio.counters().forged == 5);
}

TEST_CASE("SecureTransport: a wrong-size 2016 payload is not sent, a short buffer is refused") {
  Pair p;
  p.connect();
  std::array<std::byte, 16> short_payload{};
  CHECK(p.pc.send(short_payload) == transport::TransportStatus::error);
  CHECK(p.link.a_to_b().size() == 0);
  REQUIRE(p.pc.send(setpoint_bytes(0)) == transport::TransportStatus::ok);
  std::array<std::byte, 8> tiny{};
  CHECK(p.sbrio.receive(tiny, 0ns).status == transport::TransportStatus::rejected);
}

TEST_CASE("SecureTransport: exchanges allocate nothing") {
  Pair p;
  p.connect();
  const auto sp = setpoint_bytes(0x0F);
  const auto st = state_bytes();
  const long allocations = endohaptics::test::allocations_during([&] {
    std::array<std::byte, 64> buffer{};
    for (int i = 0; i < 1000; ++i) {
      REQUIRE(p.pc.send(sp) == transport::TransportStatus::ok);
      REQUIRE(p.sbrio.receive(buffer, 0ns).status == transport::TransportStatus::ok);
      REQUIRE(p.sbrio.send(st) == transport::TransportStatus::ok);
      REQUIRE(p.pc.receive(buffer, 0ns).status == transport::TransportStatus::ok);
    }
  });
  CHECK(allocations == 0);
}

}  // namespace protocol_secure_transport_test
