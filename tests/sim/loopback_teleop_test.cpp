// The whole loop in one thread, deterministic: TeleopLoop (bridge side) -> in-memory link ->
// SbrioEmulator -> SimulatedRig, with the scripted operator, the 2016 force estimator (paced),
// the cylindrical mapping and a manual clock.
#include "alloc_counter.hpp"  // first: counts every heap allocation of this executable

#include <doctest/doctest.h>

#include <chrono>
#include <endohaptics/estimation/force_estimator.hpp>
#include <endohaptics/estimation/paced_estimator.hpp>
#include <endohaptics/kinematics/cylindrical_mapper.hpp>
#include <endohaptics/sim/sbrio_emulator.hpp>
#include <endohaptics/sim/scripted_operator.hpp>
#include <endohaptics/sim/simulated_rig.hpp>
#include <endohaptics/teleop/teleop_loop.hpp>
#include <endohaptics/transport/in_memory_transport.hpp>
#include <memory>

namespace sim_loopback_teleop_test {

namespace {

namespace transport = endohaptics::transport;
namespace sim = endohaptics::sim;
namespace tp = endohaptics::teleop;
namespace est = endohaptics::estimation;
using namespace std::chrono_literals;

using Rig = sim::SimulatedRig<4>;
using Emulator = sim::SbrioEmulator<transport::InMemoryTransport<>, Rig, endohaptics::ManualClock>;

// The PC's transport: sending hands the datagram to the emulator, which answers at once (the
// wire and the sbRIO take `latency` of simulated time).
struct EmulatedWire {
  transport::InMemoryTransport<>* pc;
  Emulator* emulator;
  endohaptics::ManualClock* clock;
  std::chrono::nanoseconds latency = 100us;
  bool unplugged = false;

  transport::TransportStatus send(std::span<const std::byte> datagram) noexcept {
    if (unplugged) return transport::TransportStatus::ok;  // lost on the wire
    const auto status = pc->send(datagram);
    clock->advance(latency);
    (void)emulator->poll(0ns);
    return status;
  }
  transport::ReceiveResult receive(std::span<std::byte> buffer,
                                   std::chrono::nanoseconds timeout) noexcept {
    const auto r = pc->receive(buffer, timeout);
    if (r.status == transport::TransportStatus::timeout) clock->advance(timeout);  // waited it out
    return r;
  }
};

struct Rigged {
  transport::InMemoryLink<> link;
  endohaptics::ManualClock clock{1s};
  Rig rig{sim::endowrist_2016_rig<4>(sim::Environment::tissue)};
  Emulator emulator{link.b(), rig, clock};
  EmulatedWire wire{&link.a(), &emulator, &clock};
  sim::ScriptedOperator<endohaptics::ManualClock> hand{clock};
  est::ForceEstimator<est::rate::Decimate> estimator{};
  est::PacedEstimator<est::ForceEstimator<est::rate::Decimate>, endohaptics::ManualClock> paced{
      estimator, clock, 1ms};
  endohaptics::kinematics::CylindricalMapper<> mapper{};
  tp::TeleopLoop<EmulatedWire, sim::ScriptedOperator<endohaptics::ManualClock>, decltype(paced),
                 endohaptics::kinematics::CylindricalMapper<>, endohaptics::ManualClock>
      loop{wire, hand, paced, mapper, clock};
};

}  // namespace

TEST_CASE("loopback teleoperation: the clamp follows the operator and grasps the tissue") {
  auto r = std::make_unique<Rigged>();
  double max_truth = 0.0, max_tracking_error_hold = 0.0;
  std::uint64_t ok = 0, n = 0;
  r->loop.run([&] { return n >= 7000; },
              [&](const tp::TickResult& t) {
                ++n;
                ok += t.ok();
                max_truth = std::max(max_truth, r->rig.truth().contact_force[2]);
                // The last 0.3 s of the open rest of each cycle (nothing touched): the clamp is
                // where the setpoint says, within the cascade's lag.
                const auto& script = r->hand.script();
                const double phase = std::fmod(static_cast<double>(n) * 1e-3, script.cycle());
                if (n > 3000 && phase > script.open_time - 0.3 && phase < script.open_time) {
                  max_tracking_error_hold = std::max(
                      max_tracking_error_hold, std::abs(t.setpoint[2] - t.measured.position[2]));
                }
              });
  CHECK(n == 7000);
  CHECK(ok >= 6990);  // all but the first exchange or so
  CHECK(r->loop.stats().decode_errors() == 0);
  CHECK(r->loop.watchdog().link_losses() == 0);
  CHECK(r->emulator.counters().answered == 7000);
  CHECK(r->emulator.counters().watchdog_trips == 0);
  CHECK(max_truth > 0.5);  // the grasp touches the tissue
  // rad: the setpoint still moves a little (the arm yields to the rendered force), so allow the
  // lag of a slow motion on top of the play (0.017 rad).
  CHECK(max_tracking_error_hold < 0.1);
  CHECK(r->hand.force().norm() <= 3.0);  // SafetyConfig::max_stylus_force
}

TEST_CASE("loopback teleoperation: link lost -> safe state, sbRIO watchdog, recovery") {
  auto r = std::make_unique<Rigged>();
  std::uint64_t n = 0;
  tp::TickResult last{};
  r->loop.run([&] { return n >= 1000; }, [&](const tp::TickResult& t) { ++n, last = t; });
  REQUIRE(last.link == tp::LinkState::up);
  r->wire.unplugged = true;
  n = 0;
  int lost_after = -1;
  r->loop.run([&] { return n >= 300; },
              [&](const tp::TickResult& t) {
                ++n;
                if (lost_after < 0 && t.link == tp::LinkState::lost)
                  lost_after = static_cast<int>(n);
                if (t.link == tp::LinkState::lost) CHECK(t.stylus_force.isZero());
              });
  CHECK(lost_after == 11);  // more than 10 consecutive misses
  r->emulator.advance_to(r->clock.now());
  CHECK(r->emulator.watchdog_tripped());  // the sbRIO disabled its motors on its own
  CHECK(r->rig.state().active_mask == 0);
  r->wire.unplugged = false;
  n = 0;
  r->loop.run([&] { return n >= 1000; }, [&](const tp::TickResult& t) { ++n, last = t; });
  CHECK(last.link == tp::LinkState::up);
  CHECK(last.force_scale == 1.0);
  CHECK(r->rig.state().active_mask == 0x0F);
  CHECK(r->loop.watchdog().recoveries() == 1);
}

TEST_CASE("loopback teleoperation: 10,000 ticks of the whole loop allocate nothing") {
  auto r = std::make_unique<Rigged>();
  std::uint64_t n = 0;
  r->loop.run([&] { return n >= 500; }, [&](const tp::TickResult&) { ++n; });  // warm-up
  n = 0;
  const long allocations = endohaptics::test::allocations_during(
      [&] { r->loop.run([&] { return n >= 10000; }, [&](const tp::TickResult&) { ++n; }); });
  CHECK(allocations == 0);
  CHECK(n == 10000);
}

}  // namespace sim_loopback_teleop_test
