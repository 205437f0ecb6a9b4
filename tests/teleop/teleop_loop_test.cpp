#include "alloc_counter.hpp"  // first: counts every heap allocation of this executable

#include <doctest/doctest.h>

#include <cmath>
#include <cstdlib>
#include <endohaptics/kinematics/cylindrical_mapper.hpp>
#include <endohaptics/teleop/teleop_loop.hpp>
#include <endohaptics/transport/fault_injecting_transport.hpp>
#include <endohaptics/transport/in_memory_transport.hpp>

namespace teleop_teleop_loop_test {

namespace {

namespace transport = endohaptics::transport;
namespace tp = endohaptics::teleop;
using Codec = endohaptics::protocol::PacketCodec<4>;
using endohaptics::test::allocations_during;
using namespace std::chrono_literals;

// A minimal emulated sbRIO for the loop's tests: enabled motors move 5 % of the way to their
// setpoint per exchange; current = 2 A/rad * (setpoint - position); replies with the state.
struct FakeSbrio {
  Codec::State state;
  std::uint64_t requests = 0;
  bool ever_enabled_before_contact = false;
  bool disobey = false;  // answers every setpoint but enables nothing (a refusing robot)

  template <typename Reply>
  void operator()(std::span<const std::byte> in, Reply& reply) noexcept {
    ++requests;
    Codec::Setpoint sp;
    if (Codec::decode_setpoint(in, sp) != endohaptics::protocol::CodecStatus::ok) return;
    if (disobey) sp.enable_mask = 0;
    for (int i = 0; i < 4; ++i) {
      if (sp.enable_mask & (1u << i)) {
        const double step = 0.05 * (sp.position[i] - state.position[i]);
        state.position[i] += step;
        state.velocity[i] = step / 1e-3;
        state.current[i] = 2.0 * (sp.position[i] - state.position[i]);
      } else {
        state.velocity[i] = 0.0;
        state.current[i] = 0.0;
      }
    }
    state.active_mask = sp.enable_mask;
    Codec::StateBytes out{};
    if (Codec::encode_state(state, out) == endohaptics::protocol::CodecStatus::ok) {
      (void)reply.send(out);
    }
  }
};

// Stylus moving on a slow circle; remembers every force it was told to render.
struct ScriptedDevice {
  int t = 0;
  bool fail = false;
  Eigen::Vector3d last_force = Eigen::Vector3d::Zero();
  double max_force = 0.0;
  bool non_finite_force = false;
  tp::DeviceStatus read(tp::StylusSample& s) noexcept {
    if (fail) return tp::DeviceStatus::error;
    const double a = 0.002 * t++;
    s.position = Eigen::Vector3d(0.15 * std::sin(a), 0.15 * std::cos(a), 0.05 * std::sin(3 * a));
    return tp::DeviceStatus::ok;
  }
  tp::DeviceStatus command_force(const Eigen::Vector3d& f) noexcept {
    if (!f.allFinite()) non_finite_force = true;
    max_force = std::max(max_force, f.norm());
    last_force = f;
    return fail ? tp::DeviceStatus::error : tp::DeviceStatus::ok;
  }
};

// Force = 1 N/A of current, in motor order; can be told to produce garbage.
struct EffortEstimator {
  bool produce_nan = false;
  bool estimate(const tp::MotorState4& m, const tp::MotorVector&, tp::MotorVector& f) noexcept {
    f = m.current;
    if (produce_nan) f[2] = std::numeric_limits<double>::quiet_NaN();
    return true;
  }
  void reset() noexcept {}
};

using Responder = transport::RespondingTransport<FakeSbrio>;
using Faulty = transport::FaultInjectingTransport<Responder>;
using Mapper = endohaptics::kinematics::CylindricalMapper<>;
using Loop =
    tp::TeleopLoop<Faulty, ScriptedDevice, EffortEstimator, Mapper, endohaptics::ManualClock>;

struct Rig {
  Responder link{FakeSbrio{}};
  Faulty faulty;
  ScriptedDevice device;
  EffortEstimator estimator;
  Mapper mapper;
  endohaptics::ManualClock clock{1s};
  Loop loop;
  explicit Rig(const transport::FaultRates& rates = {}, const tp::TeleopLoopConfig& config = {},
               std::uint64_t seed = 1)
      : faulty(link, rates, seed), loop(faulty, device, estimator, mapper, clock, config) {}

  tp::TickResult tick() {
    const auto r = loop.tick();
    clock.advance(1ms);
    return r;
  }
};

// Invariants every tick must keep, whatever the link does.
void check_invariants(const tp::TickResult& r, const Rig& rig, const tp::MotorVector& previous,
                      bool previous_valid) {
  REQUIRE(r.stylus_force.allFinite());
  REQUIRE(r.stylus_force.norm() <= rig.loop.config().safety.max_stylus_force + 1e-12);
  REQUIRE(r.setpoint.allFinite());
  const auto& cfg = rig.mapper.config();
  for (int i = 0; i < 4; ++i) {
    REQUIRE(r.setpoint[i] >= cfg.lower[i] - 1e-12);
    REQUIRE(r.setpoint[i] <= cfg.upper[i] + 1e-12);
  }
  if (previous_valid && r.enable_mask != 0) {
    const double max_step = rig.loop.config().safety.max_setpoint_rate * 1e-3 + 1e-12;
    REQUIRE((r.setpoint - previous).cwiseAbs().maxCoeff() <= max_step);
  }
}

}  // namespace

TEST_CASE("start-up: motors stay disabled until the robot's position is known") {
  Rig rig;
  auto r = rig.tick();
  // The first setpoint already gets an answer from the in-memory sbRIO; the setpoint itself
  // went out with enable mask 0.
  CHECK(r.enable_mask == 0);
  CHECK(r.link == tp::LinkState::recovering);
  CHECK(r.stylus_force.norm() == 0.0);
  r = rig.tick();
  CHECK(r.enable_mask == 0x0F);
  CHECK(r.status == tp::TickStatus::ok);
}

TEST_CASE("clean link: every tick ok, force ramps in, stats exact") {
  Rig rig;
  double previous_scale = 0.0;
  for (int i = 0; i < 2000; ++i) {
    const auto r = rig.tick();
    if (i > 0) REQUIRE(r.status == tp::TickStatus::ok);
    REQUIRE(r.force_scale >= previous_scale);  // ramp never jumps back while the link is fine
    previous_scale = r.force_scale;
  }
  CHECK(previous_scale == 1.0);  // 0.5 s ramp at 1 kHz
  CHECK(rig.loop.stats().ticks() == 2000);
  CHECK(rig.loop.stats().received() == 2000);
  CHECK(rig.loop.stats().loss_percent() == 0.0);
  CHECK(rig.loop.stats().rate() == doctest::Approx(1000.0));
  CHECK(rig.device.max_force > 0.0);  // the scripted motion produces current, hence force
}

TEST_CASE("every fault kind: never a non-finite or over-limit output, counters consistent") {
  struct Case {
    const char* name;
    transport::FaultRates rates;
  };
  const Case cases[] = {
      {"drop send", {.drop_send = 0.2}},
      {"drop receive", {.drop_receive = 0.2}},
      {"delay", {.delay = 0.2}},
      {"duplicate", {.duplicate = 0.3}},
      {"reorder", {.delay = 0.3, .reorder = 0.5}},
      {"corrupt", {.corrupt = 0.3}},
      {"truncate", {.truncate = 0.2}},
      {"everything", {0.05, 0.05, 0.05, 0.05, 0.1, 0.05, 0.2}},
  };
  for (const auto& c : cases) {
    CAPTURE(c.name);
    Rig rig(c.rates, {}, 2016);
    tp::MotorVector previous = tp::MotorVector::Zero();
    bool previous_valid = false;
    for (int i = 0; i < 5000; ++i) {
      const auto r = rig.tick();
      check_invariants(r, rig, previous, previous_valid);
      previous = r.setpoint;
      previous_valid = r.enable_mask != 0;
    }
    const auto& s = rig.loop.stats();
    const auto& f = rig.faulty.counters();
    CHECK(s.exchanges() == 5000);
    CHECK(s.received() + s.timeouts() + s.decode_errors() + s.transport_errors() +
              s.state_faults() + s.not_obeyed() ==
          5000);
    CHECK_FALSE(rig.device.non_finite_force);
    if (c.rates.drop_receive > 0 && c.rates.drop_send == 0 && c.rates.delay == 0) {
      CHECK(s.timeouts() == f.dropped_receive);
      CHECK(s.timeouts() > 800);  // 20 % of 5000 = 1000 +- 28
    }
    if (c.rates.drop_send > 0 && c.rates.drop_receive == 0) {
      CHECK(s.timeouts() == f.dropped_send);  // no request, no answer
    }
    if (c.rates.truncate > 0 && c.rates.corrupt == 0) {
      CHECK(s.decode_errors() == f.truncated);  // every truncated packet has the wrong size
    }
    if (c.rates.corrupt > 0 && c.rates.truncate == 0) {
      // A flip gives NaN/Inf or a bad mask (decode error), an impossible value (state fault), or
      // a plausible one (undetectable without a checksum: protocol v2).
      CHECK(s.decode_errors() + s.state_faults() <= f.corrupted);
      CHECK(s.decode_errors() > 0);
      CHECK(s.state_faults() > 0);
    } else if (c.rates.corrupt == 0) {
      CHECK(s.state_faults() == 0);  // the fake sbRIO itself reports only plausible states
    }
    if (c.rates.duplicate > 0) {
      CHECK(s.stale_dropped() == f.duplicated);  // duplicates are drained, newest kept
    }
  }
}

TEST_CASE_TEMPLATE_DEFINE("link loss: declared on miss 11, safe state, recovery ramps force",
                          PolicyTag, link_loss) {
  tp::TeleopLoopConfig config;
  config.safety.policy = PolicyTag::value;
  Rig rig({}, config);
  for (int i = 0; i < 1000; ++i) (void)rig.tick();
  REQUIRE(rig.device.last_force.norm() > 0.0);
  const auto held = rig.loop.tick().setpoint;
  rig.clock.advance(1ms);

  rig.faulty.set_rates({.drop_receive = 1.0});
  for (int miss = 1; miss <= 10; ++miss) {
    const auto r = rig.tick();
    REQUIRE(r.status == tp::TickStatus::degraded);
    REQUIRE(r.consecutive_misses == miss);
    REQUIRE(r.stylus_force.norm() > 0.0);  // last estimate held through a short gap
  }
  auto r = rig.tick();  // miss 11: "superior to 10"
  CHECK(r.status == tp::TickStatus::link_lost);
  CHECK(r.stylus_force.norm() == 0.0);
  CHECK(rig.loop.watchdog().link_losses() == 1);
  for (int i = 0; i < 200; ++i) {
    r = rig.tick();
    REQUIRE(r.status == tp::TickStatus::link_lost);
    REQUIRE(r.stylus_force.norm() == 0.0);
    switch (PolicyTag::value) {
      case tp::SafeStatePolicy::disable_motors:
        REQUIRE(r.enable_mask == 0);
        break;
      case tp::SafeStatePolicy::hold_position:
        REQUIRE(r.enable_mask == 0x0F);
        REQUIRE(r.setpoint == rig.loop.tick().setpoint);  // frozen
        rig.clock.advance(1ms);
        break;
      case tp::SafeStatePolicy::zero_force:
        REQUIRE(r.enable_mask == 0x0F);
        break;
    }
  }
  (void)held;

  rig.faulty.set_rates({});
  r = rig.tick();
  CHECK(r.link == tp::LinkState::recovering);
  CHECK(rig.loop.watchdog().recoveries() == 1);
  double previous = r.stylus_force.norm();
  CHECK(previous <= 3.0 * 1e-3 / 0.5 + 1e-12);  // one ramp step of a <= 3 N force
  for (int i = 0; i < 600; ++i) {
    r = rig.tick();
    REQUIRE(r.status == tp::TickStatus::ok);
    // No jolt: the force grows at most by the ramp slope (3 N / 0.5 s) plus the signal's change.
    REQUIRE(r.stylus_force.norm() - previous <= 3.0 * 1e-3 / 0.5 + 0.05);
    previous = r.stylus_force.norm();
  }
  CHECK(r.link == tp::LinkState::up);
  CHECK(r.force_scale == 1.0);
}

template <tp::SafeStatePolicy P>
struct Policy {
  static constexpr tp::SafeStatePolicy value = P;
};
TEST_CASE_TEMPLATE_INVOKE(link_loss, Policy<tp::SafeStatePolicy::hold_position>,
                          Policy<tp::SafeStatePolicy::disable_motors>,
                          Policy<tp::SafeStatePolicy::zero_force>);

TEST_CASE("lost link: disable_motors by default, and a hold is bounded by max_hold_time") {
  CHECK(tp::SafetyConfig{}.policy == tp::SafeStatePolicy::disable_motors);
  for (const auto policy : {tp::SafeStatePolicy::hold_position, tp::SafeStatePolicy::zero_force}) {
    CAPTURE(to_string(policy));
    tp::TeleopLoopConfig config;
    config.safety.policy = policy;
    config.safety.max_hold_time = 0.1;
    Rig rig({}, config);
    for (int i = 0; i < 300; ++i) (void)rig.tick();
    rig.faulty.set_rates({.drop_receive = 1.0});
    tp::TickResult r;
    int ticks_lost = 0;
    int held_enabled = 0;
    for (int i = 0; i < 400; ++i) {
      r = rig.tick();
      if (r.link != tp::LinkState::lost) continue;
      ++ticks_lost;
      if (r.enable_mask != 0) ++held_enabled;
      // Enabled only within max_hold_time (100 ticks of 1 ms) of the loss, released after.
      REQUIRE((r.enable_mask == 0) == (ticks_lost > 101));
    }
    CHECK(held_enabled >= 99);
    CHECK(r.enable_mask == 0);
    // Back: the motors were released, so the limiter restarts from the measured position.
    rig.faulty.set_rates({});
    r = rig.tick();
    CHECK(r.link == tp::LinkState::recovering);
  }
  tp::SafetyConfig safety;
  safety.max_hold_time = 0.0;
  CHECK_THROWS_WITH_AS(safety.validate(), doctest::Contains("max_hold_time must be in (0, 60] s"),
                       endohaptics::Error);
}

TEST_CASE("garbage from the estimator or the device never reaches the other side") {
  Rig rig;
  for (int i = 0; i < 100; ++i) (void)rig.tick();
  rig.estimator.produce_nan = true;
  auto r = rig.tick();
  CHECK(r.estimator_rejected);
  CHECK(r.stylus_force.allFinite());
  CHECK(r.stylus_force.norm() == 0.0);
  rig.estimator.produce_nan = false;

  rig.device.fail = true;
  const auto before = rig.loop.tick().setpoint;
  rig.clock.advance(1ms);
  r = rig.tick();
  CHECK(r.status == tp::TickStatus::device_error);
  CHECK(r.stylus_force.norm() == 0.0);
  CHECK(r.setpoint == before);  // robot held while the operator's input is unknown
}

TEST_CASE("a lost operator follows the lost link's rules: held, released, resumed without a jump") {
  for (const auto policy :
       {tp::SafeStatePolicy::disable_motors, tp::SafeStatePolicy::hold_position}) {
    CAPTURE(static_cast<int>(policy));
    tp::TeleopLoopConfig config;
    config.safety.policy = policy;
    config.safety.max_hold_time = 0.1;
    Rig rig({}, config);
    for (int i = 0; i < 300; ++i) (void)rig.tick();
    rig.device.fail = true;
    const auto held = rig.loop.tick().setpoint;
    rig.clock.advance(1ms);
    for (int i = 0; i < 200; ++i) {
      const auto r = rig.tick();
      CHECK(r.status == tp::TickStatus::device_error);
      CHECK(r.setpoint == held);
      CHECK(r.stylus_force.norm() == 0.0);
      // disable_motors: released at once; hold_position: enabled within max_hold_time (100 ms).
      const bool enabled = policy == tp::SafeStatePolicy::hold_position && i < 100;
      CHECK(r.enable_mask == (enabled ? 0x0F : 0));
    }
    // Back: the limiter starts from where the robot is, and each step stays within the rate.
    rig.device.fail = false;
    auto previous = rig.loop.tick().setpoint;
    rig.clock.advance(1ms);
    for (int i = 0; i < 100; ++i) {
      const auto r = rig.tick();
      CHECK(r.enable_mask == 0x0F);
      CHECK((r.setpoint - previous).cwiseAbs().maxCoeff() <=
            config.safety.max_setpoint_rate * 1e-3 + 1e-12);
      previous = r.setpoint;
    }
  }
}

TEST_CASE("run() paces on absolute deadlines and stops on request") {
  Rig rig;
  int seen = 0;
  const auto n = rig.loop.run([&] { return seen >= 250; }, [&](const tp::TickResult&) { ++seen; });
  CHECK(n == 250);
  CHECK(rig.loop.stats().rate() == doctest::Approx(1000.0));
  CHECK(rig.clock.now() == 1s + 250ms);
}

TEST_CASE("no heap allocation in 10,000 ticks after warm-up") {
  Rig rig({.drop_receive = 0.05, .corrupt = 0.05, .truncate = 0.02}, {}, 3);
  for (int i = 0; i < 100; ++i) (void)rig.tick();
  const long allocations = allocations_during([&] {
    for (int i = 0; i < 10000; ++i) {
      const auto r = rig.loop.tick();
      rig.clock.advance(1ms);
      (void)r;
    }
  });
  CHECK(allocations == 0);
  CHECK(rig.loop.stats().ticks() == 10100);
}

namespace {

// CylindricalMapper's shape without the noexcept: one or both per-tick functions may throw.
struct ThrowingMapper {
  Mapper inner;
  auto map_position(const Eigen::Vector3d& p, tp::MotorVector& s) {
    return inner.map_position(p, s);
  }
  auto map_force(const tp::MotorVector& f, Eigen::Vector3d& out) { return inner.map_force(f, out); }
};
struct ThrowingForceMapper {
  Mapper inner;
  auto map_position(const Eigen::Vector3d& p, tp::MotorVector& s) noexcept {
    return inner.map_position(p, s);
  }
  auto map_force(const tp::MotorVector& f, Eigen::Vector3d& out) { return inner.map_force(f, out); }
};
struct ThrowingPositionMapper {
  Mapper inner;
  auto map_position(const Eigen::Vector3d& p, tp::MotorVector& s) {
    return inner.map_position(p, s);
  }
  auto map_force(const tp::MotorVector& f, Eigen::Vector3d& out) noexcept {
    return inner.map_force(f, out);
  }
};

static_assert(tp::TeleopMapper<Mapper>);
static_assert(!tp::TeleopMapper<ThrowingMapper>);
static_assert(!tp::TeleopMapper<ThrowingForceMapper>);
static_assert(!tp::TeleopMapper<ThrowingPositionMapper>);

}  // namespace

TEST_CASE("TeleopMapper requires noexcept map_position and map_force") {
  CHECK(tp::TeleopMapper<Mapper>);
  CHECK_FALSE(tp::TeleopMapper<ThrowingMapper>);
  CHECK_FALSE(tp::TeleopMapper<ThrowingForceMapper>);
  CHECK_FALSE(tp::TeleopMapper<ThrowingPositionMapper>);
}

TEST_CASE("a stall (clock jumps 100 ms): rate limit and force ramp still hold per nominal period") {
  auto check_stall = [](const tp::TeleopLoopConfig& config, double bound_s) {
    CHECK(std::chrono::duration<double>(config.max_tick_dt()).count() == bound_s);
    Rig rig({}, config);
    tp::TickResult before;
    for (int i = 0; i < 100; ++i) before = rig.tick();  // link up, force ramp under way
    REQUIRE(before.status == tp::TickStatus::ok);
    REQUIRE(before.force_scale > 0.0);
    REQUIRE(before.force_scale < 1.0);
    rig.clock.advance(100ms);  // the tick thread stalled
    rig.device.t += 500;       // meanwhile the stylus moved a long way (roll: 0.7 rad)
    const auto after = rig.tick();
    REQUIRE(after.status == tp::TickStatus::ok);
    CHECK(after.rate_limited);
    const double max_step = config.safety.max_setpoint_rate * bound_s;
    CHECK((after.setpoint - before.setpoint).cwiseAbs().maxCoeff() <= max_step + 1e-12);
    CHECK(after.force_scale - before.force_scale <=
          bound_s / config.safety.force_ramp_time + 1e-12);
  };
  SUBCASE("period 1 ms: dt at most the period") { check_stall(tp::TeleopLoopConfig{}, 1e-3); }
  SUBCASE("period 0 (as fast as possible): dt at most the receive timeout (here 2 ms)") {
    tp::TeleopLoopConfig config;
    config.period = 0ns;
    config.receive_timeout = 2ms;
    check_stall(config, 2e-3);
  }
  SUBCASE("period 0 with receive timeout 0.5 ms: dt at most 1 ms") {
    tp::TeleopLoopConfig config;
    config.period = 0ns;
    config.receive_timeout = 500us;
    check_stall(config, 1e-3);
  }
}

TEST_CASE("an enable_mask with a bit at or above the motor count is refused at construction") {
  tp::TeleopLoopConfig config;
  config.safety.enable_mask = 0x10;
  CHECK_THROWS_WITH_AS(Rig({}, config), doctest::Contains("enable_mask"), endohaptics::Error);
  tp::SafetyConfig safety;
  safety.enable_mask = 0x10;
  CHECK_THROWS_WITH_AS(safety.validate(),
                       "SafetyConfig: enable_mask must be <= 0x0F (bits 0..3: 4 motors), got 0x10",
                       endohaptics::Error);
  safety.enable_mask = 0x80;
  CHECK_THROWS_WITH_AS(safety.validate(), doctest::Contains("got 0x80"), endohaptics::Error);
  for (const std::uint8_t ok : std::initializer_list<std::uint8_t>{0x00, 0x01, 0x0F}) {
    safety.enable_mask = ok;
    CHECK_NOTHROW(safety.validate());
  }
}

TEST_CASE("link up means obeyed: a robot that answers but leaves the enabled motors off is lost") {
  tp::TeleopLoopConfig config;
  config.safety.policy = tp::SafeStatePolicy::hold_position;  // keeps asking: stays lost
  Rig rig({}, config);
  rig.link.responder().disobey = true;
  tp::TickResult r;
  for (int i = 0; i < 5; ++i) r = rig.tick();
  // First contact: nothing enabled yet, so the answers are obeyed; then the motors are enabled.
  CHECK(r.enable_mask == 0x0F);
  const int grace = static_cast<int>(rig.loop.config().safety.activation_timeout / 1e-3);
  for (int i = 0; i < grace - 6; ++i) {
    r = rig.tick();
    REQUIRE(r.not_obeyed_mask == 0);  // within the activation timeout: still fine
  }
  int not_obeyed = 0;
  for (int i = 0; i < 40; ++i) {
    r = rig.tick();
    if (r.exchange == tp::TickOutcome::not_obeyed) ++not_obeyed;
  }
  CHECK(not_obeyed >= 35);
  CHECK(r.not_obeyed_mask == 0x0F);
  CHECK(r.link == tp::LinkState::lost);
  CHECK(r.stylus_force.isZero());
  CHECK(rig.loop.stats().not_obeyed() == static_cast<std::uint64_t>(not_obeyed));
  CHECK(rig.loop.stats().received() < 60);
  // The robot obeys again: the link recovers.
  rig.link.responder().disobey = false;
  for (int i = 0; i < 5; ++i) r = rig.tick();
  CHECK(r.exchange == tp::TickOutcome::received);
  CHECK(r.link == tp::LinkState::recovering);
}

TEST_CASE("activation_timeout: an obeying robot is never counted against it, bounds refused") {
  Rig rig;
  for (int i = 0; i < 200; ++i) (void)rig.tick();
  CHECK(rig.loop.stats().not_obeyed() == 0);
  CHECK(rig.loop.stats().received() == 200);
  tp::SafetyConfig safety;
  for (const double bad : {0.0, -1.0, 10.5, std::numeric_limits<double>::quiet_NaN()}) {
    safety.activation_timeout = bad;
    CHECK_THROWS_WITH_AS(safety.validate(),
                         doctest::Contains("activation_timeout must be in (0, 10] s"),
                         endohaptics::Error);
  }
}

}  // namespace teleop_teleop_loop_test
