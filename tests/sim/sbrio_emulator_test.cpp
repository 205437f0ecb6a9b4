#include "alloc_counter.hpp"  // first: counts every heap allocation of this executable

#include <doctest/doctest.h>

#include <array>
#include <chrono>
#include <endohaptics/sim/sbrio_emulator.hpp>
#include <endohaptics/transport/in_memory_transport.hpp>
#include <vector>

namespace sim_sbrio_emulator_test {

namespace {

namespace transport = endohaptics::transport;
namespace sim = endohaptics::sim;
using Codec = endohaptics::protocol::PacketCodec<4>;
using namespace std::chrono_literals;

// A rig that records what it was told: enabled motors sit at their setpoint.
struct FakeRig {
  Codec::Setpoint commanded{};
  double time = 0.0;          // s advanced in total
  double disabled_at = -1.0;  // s, time of the first command with every motor disabled
  int commands = 0;
  int advances = 0;
  double longest_advance = 0.0;  // s

  void command(const Codec::Setpoint& sp) noexcept {
    if (commanded.enable_mask != 0 && sp.enable_mask == 0 && disabled_at < 0) disabled_at = time;
    commanded = sp;
    ++commands;
  }
  int advance(double dt) noexcept {
    time += dt;
    ++advances;
    longest_advance = std::max(longest_advance, dt);
    return 0;
  }
  Codec::State state() const noexcept {
    Codec::State s;
    for (int i = 0; i < 4; ++i) {
      if ((commanded.enable_mask >> i) & 1) s.position[i] = commanded.position[i];
    }
    s.current.setConstant(time);  // lets a test see when the answer was made
    s.active_mask = commanded.enable_mask;
    return s;
  }
};
static_assert(sim::EmulatedRig<FakeRig, 4>);

struct Fixture {
  transport::InMemoryLink<> link;
  endohaptics::ManualClock clock{1s};
  FakeRig rig;
  sim::SbrioEmulator<transport::InMemoryTransport<>, FakeRig, endohaptics::ManualClock> emulator{
      link.b(), rig, clock};

  void send_setpoint(const Eigen::Vector4d& position, std::uint8_t mask) {
    Codec::Setpoint sp;
    sp.position = position;
    sp.enable_mask = mask;
    Codec::SetpointBytes bytes{};
    REQUIRE(Codec::encode_setpoint(sp, bytes) == endohaptics::protocol::CodecStatus::ok);
    REQUIRE(link.a().send(bytes) == transport::TransportStatus::ok);
  }
  bool receive_state(Codec::State& state) {
    std::array<std::byte, 128> buffer{};
    const auto r = link.a().receive(buffer, 0ns);
    if (r.status != transport::TransportStatus::ok) return false;
    return Codec::decode_state(std::span<const std::byte>(buffer.data(), r.size), state) ==
           endohaptics::protocol::CodecStatus::ok;
  }
};

}  // namespace

TEST_CASE("a valid setpoint packet is applied and answered with the rig's state") {
  Fixture f;
  CHECK(f.rig.commanded.enable_mask == 0);  // disabled until the PC says otherwise
  f.clock.advance(2ms);
  f.send_setpoint(Eigen::Vector4d(0.1, -0.2, 0.3, -0.4), 0x05);
  CHECK(f.emulator.poll(0ns) == sim::PollEvent::answered);
  Codec::State state;
  REQUIRE(f.receive_state(state));
  CHECK(state.active_mask == 0x05);
  CHECK(state.position[0] == doctest::Approx(0.1));
  CHECK(state.position[1] == 0.0);  // not enabled: does not follow
  CHECK(state.position[2] == doctest::Approx(0.3));
  CHECK(state.current[0] == doctest::Approx(0.002));  // the rig ran 2 ms before answering
  CHECK(f.emulator.counters().received == 1);
  CHECK(f.emulator.counters().answered == 1);
  CHECK(f.emulator.poll(0ns) == sim::PollEvent::idle);
  CHECK(!f.receive_state(state));  // idle polls answer nothing
}

TEST_CASE("garbled, short and long datagrams are rejected, counted and not answered") {
  Fixture f;
  const std::array<std::size_t, 4> sizes{0, 16, 18, 49};
  for (const std::size_t n : sizes) {
    std::vector<std::byte> junk(n, std::byte{0x7f});
    REQUIRE(f.link.a().send(junk) == transport::TransportStatus::ok);
    CHECK(f.emulator.poll(0ns) == sim::PollEvent::rejected);
  }
  // Right size, but a NaN setpoint (0x7fc00000) and a mask bit above motor 3.
  std::array<std::byte, Codec::setpoint_packet_size> nan{};
  nan[0] = std::byte{0x7f};
  nan[1] = std::byte{0xc0};
  REQUIRE(f.link.a().send(nan) == transport::TransportStatus::ok);
  CHECK(f.emulator.poll(0ns) == sim::PollEvent::rejected);
  std::array<std::byte, Codec::setpoint_packet_size> mask{};
  mask.back() = std::byte{0x10};
  REQUIRE(f.link.a().send(mask) == transport::TransportStatus::ok);
  CHECK(f.emulator.poll(0ns) == sim::PollEvent::rejected);
  CHECK(f.emulator.counters().rejected == 6);
  CHECK(f.emulator.counters().rejected_size == 4);  // 0, 16 (decoder), 18, 49 (too long)
  CHECK(f.emulator.counters().rejected_non_finite == 1);
  CHECK(f.emulator.counters().rejected_mask == 1);
  CHECK(f.emulator.counters().answered == 0);
  CHECK(f.rig.commands == 1);  // only the constructor's "everything disabled"
  Codec::State state;
  CHECK(!f.receive_state(state));
}

TEST_CASE("junk arriving after a valid setpoint cannot displace it (newest valid packet wins)") {
  // Before: the emulator kept the newest datagram, so 0-byte datagrams from another local sender
  // made it drop the bridge's setpoint (60 % loss, 17 link losses at the bridge in the field test).
  Fixture f;
  f.send_setpoint(Eigen::Vector4d(0.1, 0.2, 0.3, 0.4), 0x0F);
  for (int i = 0; i < 10; ++i) REQUIRE(f.link.a().send({}) == transport::TransportStatus::ok);
  std::array<std::byte, Codec::setpoint_packet_size> nan{};
  nan[0] = std::byte{0x7f};
  nan[1] = std::byte{0xc0};
  REQUIRE(f.link.a().send(nan) == transport::TransportStatus::ok);
  CHECK(f.emulator.poll(0ns) == sim::PollEvent::answered);
  CHECK(f.rig.commanded.position[2] == doctest::Approx(0.3));
  CHECK(f.emulator.counters().received == 1);
  CHECK(f.emulator.counters().rejected == 11);
  CHECK(f.emulator.counters().rejected_size == 10);
  CHECK(f.emulator.counters().rejected_non_finite == 1);
  Codec::State state;
  CHECK(f.receive_state(state));

  // Two valid setpoints: the older is drained unanswered, counted as stale.
  f.send_setpoint(Eigen::Vector4d(0.0, 0.0, 0.1, 0.0), 0x0F);
  f.send_setpoint(Eigen::Vector4d(0.0, 0.0, 0.2, 0.0), 0x0F);
  REQUIRE(f.link.a().send({}) == transport::TransportStatus::ok);
  CHECK(f.emulator.poll(0ns) == sim::PollEvent::answered);
  CHECK(f.rig.commanded.position[2] == doctest::Approx(0.2));
  CHECK(f.emulator.counters().stale_dropped == 1);
}

TEST_CASE("the watchdog disables every motor 100 ms after the last valid packet, not later") {
  Fixture f;
  f.send_setpoint(Eigen::Vector4d::Constant(0.2), 0x0F);
  REQUIRE(f.emulator.poll(0ns) == sim::PollEvent::answered);
  const double t_packet = f.rig.time;
  f.clock.advance(99ms);
  f.emulator.advance_to(f.clock.now());
  CHECK(!f.emulator.watchdog_tripped());
  CHECK(f.rig.commanded.enable_mask == 0x0F);
  f.clock.advance(250ms);  // one long pause: the trip must still happen at +100 ms in rig time
  CHECK(f.emulator.poll(0ns) == sim::PollEvent::idle);
  CHECK(f.emulator.watchdog_tripped());
  CHECK(f.rig.commanded.enable_mask == 0);
  CHECK(f.rig.commanded.position[0] == doctest::Approx(0.2));  // positions kept, motors coast
  CHECK(f.rig.disabled_at - t_packet == doctest::Approx(0.100).epsilon(1e-9));
  CHECK(f.rig.time - t_packet == doctest::Approx(0.349));
  CHECK(f.emulator.counters().watchdog_trips == 1);

  // A packet again: the motors follow again, and the watchdog is re-armed.
  f.send_setpoint(Eigen::Vector4d::Constant(0.1), 0x0F);
  CHECK(f.emulator.poll(0ns) == sim::PollEvent::answered);
  CHECK(!f.emulator.watchdog_tripped());
  CHECK(f.rig.commanded.enable_mask == 0x0F);
  f.clock.advance(150ms);
  f.emulator.advance_to(f.clock.now());
  CHECK(f.emulator.counters().watchdog_trips == 2);
}

TEST_CASE("a disabled rig does not trip the watchdog, and long pauses run in bounded chunks") {
  Fixture f;
  f.clock.advance(3500ms);
  CHECK(f.emulator.poll(0ns) == sim::PollEvent::idle);
  CHECK(f.emulator.counters().watchdog_trips == 0);
  CHECK(f.rig.time == doctest::Approx(3.5));
  CHECK(f.rig.longest_advance <= 1.0);  // EmulatorConfig::max_advance
  CHECK(f.rig.advances >= 4);
}

TEST_CASE("a bad configuration is refused with a message") {
  transport::InMemoryLink<> link;
  endohaptics::ManualClock clock;
  FakeRig rig;
  sim::EmulatorConfig config;
  config.watchdog_timeout = 0ns;
  using Emulator =
      sim::SbrioEmulator<transport::InMemoryTransport<>, FakeRig, endohaptics::ManualClock>;
  CHECK_THROWS_WITH_AS(Emulator(link.b(), rig, clock, config),
                       doctest::Contains("watchdog_timeout must be > 0"), endohaptics::Error);
}

TEST_CASE("polling allocates nothing") {
  Fixture f;
  for (int i = 0; i < 10; ++i) {  // warm-up
    f.send_setpoint(Eigen::Vector4d::Constant(0.01 * i), 0x0F);
    (void)f.emulator.poll(0ns);
    Codec::State s;
    (void)f.receive_state(s);
  }
  const long allocations = endohaptics::test::allocations_during([&] {
    for (int i = 0; i < 10000; ++i) {
      f.clock.advance(1ms);
      Codec::Setpoint sp;
      sp.position.setConstant(1e-4 * (i % 100));
      sp.enable_mask = 0x0F;
      Codec::SetpointBytes bytes{};
      (void)Codec::encode_setpoint(sp, bytes);
      (void)f.link.a().send(bytes);
      (void)f.emulator.poll(0ns);
      std::array<std::byte, 64> buffer{};
      (void)f.link.a().receive(buffer, 0ns);
    }
  });
  CHECK(allocations == 0);
  CHECK(f.emulator.counters().answered == 10010);
  // The counter sees allocations, so the check above can fail.
  CHECK(endohaptics::test::allocations_during([] {
          int* volatile p = new int(3);
          delete p;
        }) == 1);
}

TEST_CASE("with a sample period the rig is seen on an exact grid, whatever the packets' timing") {
  transport::InMemoryLink<> link;
  endohaptics::ManualClock clock{1s};
  FakeRig rig;
  sim::EmulatorConfig config;
  config.sample_period = 1ms;
  sim::SbrioEmulator<transport::InMemoryTransport<>, FakeRig, endohaptics::ManualClock> emulator(
      link.b(), rig, clock, config);
  struct Seen {
    std::chrono::nanoseconds time;
    double rig_time;
    std::uint8_t mask;
  };
  std::vector<Seen> seen;
  seen.reserve(16);
  const auto sampler = [&](std::chrono::nanoseconds t, const Codec::Setpoint& sp,
                           const FakeRig& r) noexcept {
    seen.push_back({t, r.time, sp.enable_mask});
  };
  // Polls at irregular times: 0.3, 2.6 (a packet arrived before it), 2.9, 4.0 ms.
  clock.advance(300us);
  CHECK(emulator.poll(0ns, sampler) == sim::PollEvent::idle);
  clock.advance(2300us);
  Codec::Setpoint sp;
  sp.enable_mask = 0b0001;
  Codec::SetpointBytes bytes{};
  REQUIRE(Codec::encode_setpoint(sp, bytes) == endohaptics::protocol::CodecStatus::ok);
  REQUIRE(link.a().send(bytes) == transport::TransportStatus::ok);
  CHECK(emulator.poll(0ns, sampler) == sim::PollEvent::answered);
  clock.advance(300us);
  CHECK(emulator.poll(0ns, sampler) == sim::PollEvent::idle);
  clock.advance(1100us);
  CHECK(emulator.poll(0ns, sampler) == sim::PollEvent::idle);
  // Instants 0, 1, 2, 3, 4 ms after construction; the rig stopped at each (its own time), and
  // the setpoint applied at 2.6 ms seen from the 3 ms instant on.
  REQUIRE(seen.size() == 5);
  for (std::size_t k = 0; k < seen.size(); ++k) {
    CHECK(seen[k].time == 1s + std::chrono::milliseconds(k));
    CHECK(seen[k].rig_time == doctest::Approx(1e-3 * static_cast<double>(k)));
    CHECK(seen[k].mask == (k >= 3 ? 0b0001 : 0));
  }
  CHECK(rig.time == doctest::Approx(4e-3));
  // No grid by default; a negative period is refused.
  config.sample_period = -1ms;
  CHECK_THROWS_AS(config.validate(), endohaptics::Error);
}

}  // namespace sim_sbrio_emulator_test
