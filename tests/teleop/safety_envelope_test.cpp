// The safety envelope (docs/safety.md): whatever the robot reports, every setpoint lies inside the
// joint range, every stylus force inside the device's limit, and an implausible state is a fault
// that is counted and never followed. Property tests drive the loop with random and adversarial
// state streams and check the envelope on every tick.
#include "alloc_counter.hpp"  // first: counts every heap allocation of this executable

#include <doctest/doctest.h>

#include <algorithm>
#include <bit>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <endohaptics/kinematics/cylindrical_mapper.hpp>
#include <endohaptics/teleop/teleop_loop.hpp>
#include <endohaptics/transport/in_memory_transport.hpp>
#include <limits>
#include <random>

namespace teleop_safety_envelope_test {

namespace {

namespace transport = endohaptics::transport;
namespace tp = endohaptics::teleop;
using Codec = endohaptics::protocol::PacketCodec<4>;
using endohaptics::test::allocations_during;
using namespace std::chrono_literals;

// What the hostile sbRIO answers to one setpoint.
enum class Answer : int {
  honest,         // the plausible state of a rig that follows its setpoints
  huge_position,  // position +-50 rad (the tester's first attack)
  float_max,      // +-3e38 in every field
  position_edge,  // just outside the range plus margin
  jump,           // in range, but far from the last position
  fast,           // velocity beyond the motor's no-load speed
  overcurrent,    // current beyond the ESCON's peak
  nan_bits,       // NaN in a field (the codec refuses)
  bad_mask,       // active bit 7
  wrong_length,   // 0..60 bytes of noise
  duplicate,      // the honest answer twice
  flood,          // the honest answer, then 20 junk datagrams
  silent,         // nothing
  count
};

// An sbRIO stand-in that answers each setpoint per `pick` (or at random with `seed`), and keeps
// a plausible "true" rig state underneath: enabled motors move 5 % towards their setpoint.
struct HostileSbrio {
  Codec::State truth;
  std::mt19937_64 rng{1};
  Answer fixed = Answer::count;  // count: random answers
  int honest_percent = 50;       // with random answers: this share is honest

  Answer pick() {
    if (fixed != Answer::count) return fixed;
    if (static_cast<int>(rng() % 100) < honest_percent) return Answer::honest;
    return static_cast<Answer>(rng() % static_cast<std::uint64_t>(Answer::count));
  }

  template <typename Reply>
  void operator()(std::span<const std::byte> in, Reply& reply) noexcept {
    Codec::Setpoint sp;
    if (Codec::decode_setpoint(in, sp) == endohaptics::protocol::CodecStatus::ok) {
      for (int i = 0; i < 4; ++i) {
        const bool on = (sp.enable_mask >> i) & 1u;
        const double step = on ? 0.05 * (sp.position[i] - truth.position[i]) : 0.0;
        truth.position[i] += step;
        truth.velocity[i] = step / 1e-3;
        truth.current[i] = on ? 1.5 * (sp.position[i] - truth.position[i]) : 0.0;
      }
      truth.active_mask = sp.enable_mask;
    }
    Codec::State s = truth;
    const double sign = rng() % 2 ? 1.0 : -1.0;
    const int motor = static_cast<int>(rng() % 4);
    switch (pick()) {
      case Answer::honest:
      case Answer::count:
        break;
      case Answer::huge_position:
        s.position[motor] = 50.0 * sign;
        break;
      case Answer::float_max:
        s.position.setConstant(3e38 * sign);
        s.velocity.setConstant(-3e38 * sign);
        s.current.setConstant(3e38);
        break;
      case Answer::position_edge:
        s.position[motor] = sign * (1.028 + 0.2 + 1e-6);
        break;
      case Answer::jump:
        s.position[motor] = truth.position[motor] > 0 ? -1.0 : 1.0;
        break;
      case Answer::fast:
        s.velocity[motor] = sign * 41.0;
        break;
      case Answer::overcurrent:
        s.current[motor] = sign * 16.0;
        break;
      case Answer::nan_bits: {
        Codec::StateBytes bytes{};
        (void)Codec::encode_state(truth, bytes);
        const std::size_t at = 4 * (rng() % 12);  // a quiet NaN, big-endian as on the wire
        bytes[at] = std::byte{0x7F};
        bytes[at + 1] = std::byte{0xC0};
        bytes[at + 2] = std::byte{0};
        bytes[at + 3] = std::byte{0};
        (void)reply.send(bytes);
        return;
      }
      case Answer::bad_mask: {
        Codec::StateBytes bytes{};
        (void)Codec::encode_state(truth, bytes);
        bytes.back() = std::byte{0x80};
        (void)reply.send(bytes);
        return;
      }
      case Answer::wrong_length: {
        std::array<std::byte, 60> noise{};
        for (auto& b : noise) b = std::byte{static_cast<unsigned char>(rng())};
        std::size_t n = rng() % noise.size();
        if (n == Codec::state_packet_size) n = 0;
        (void)reply.send(std::span<const std::byte>(noise.data(), n));
        return;
      }
      case Answer::duplicate:
        send_state(s, reply);
        break;
      case Answer::flood: {
        send_state(s, reply);
        for (int k = 0; k < 20; ++k) {
          std::array<std::byte, 7> junk{};
          (void)reply.send(std::span<const std::byte>(junk.data(), rng() % 2 ? 0 : junk.size()));
        }
        return;
      }
      case Answer::silent:
        return;
    }
    send_state(s, reply);
  }

  template <typename Reply>
  static void send_state(const Codec::State& s, Reply& reply) noexcept {
    Codec::StateBytes bytes{};
    if (Codec::encode_state(s, bytes) == endohaptics::protocol::CodecStatus::ok) {
      (void)reply.send(bytes);
    }
  }
};

// A stylus that wanders anywhere, far outside the workspace too.
struct WildDevice {
  std::mt19937_64 rng{7};
  Eigen::Vector3d position{0.13, 0.0, 0.14};
  tp::DeviceStatus read(tp::StylusSample& s) noexcept {
    std::uniform_real_distribution<double> step(-0.02, 0.02);
    for (int k = 0; k < 3; ++k) position[k] = std::clamp(position[k] + step(rng), -1.0, 1.0);
    s.position = position;
    return tp::DeviceStatus::ok;
  }
  tp::DeviceStatus command_force(const Eigen::Vector3d&) noexcept { return tp::DeviceStatus::ok; }
};

// Force = 10 N/A of current (a badly scaled model: pushes every limit).
struct LoudEstimator {
  bool estimate(const tp::MotorState4& m, const tp::MotorVector&, tp::MotorVector& f) noexcept {
    f = 10.0 * m.current;
    return true;
  }
  void reset() noexcept {}
};

using Link = transport::RespondingTransport<HostileSbrio, 64, 32>;
using Mapper = endohaptics::kinematics::CylindricalMapper<>;
using Loop = tp::TeleopLoop<Link, WildDevice, LoudEstimator, Mapper, endohaptics::ManualClock>;

struct Rig {
  Link link{HostileSbrio{}};
  WildDevice device;
  LoudEstimator estimator;
  Mapper mapper;
  endohaptics::ManualClock clock{1s};
  Loop loop;
  explicit Rig(const tp::TeleopLoopConfig& config = {})
      : loop(link, device, estimator, mapper, clock, config) {}
  tp::TickResult tick() {
    const auto r = loop.tick();
    clock.advance(1ms);
    return r;
  }
};

// Answers every setpoint with a state packet of uniformly random bytes (mask bits 0..3).
struct RandomBytes {
  std::mt19937_64 rng{11};
  template <typename Reply>
  void operator()(std::span<const std::byte>, Reply& reply) noexcept {
    Codec::StateBytes bytes{};
    for (auto& b : bytes) b = std::byte{static_cast<unsigned char>(rng())};
    bytes.back() = std::byte{static_cast<unsigned char>(rng() % 16)};
    (void)reply.send(bytes);
  }
};

// The envelope, checked on one tick. `previous`: the tick before (its setpoint and mask);
// `recovered`: the state `previous` received ended a loss (link lost -> recovering), so this
// tick's setpoint starts from the measured position of every joint the sbRIO reported released.
void check_envelope(const tp::TickResult& r, const tp::TickResult& previous,
                    const tp::TeleopLoopConfig& config, bool recovered = false) {
  const auto& s = config.safety;
  REQUIRE(r.setpoint.allFinite());
  for (int i = 0; i < 4; ++i) {
    REQUIRE(r.setpoint[i] >= s.joint_lower[i]);
    REQUIRE(r.setpoint[i] <= s.joint_upper[i]);
  }
  REQUIRE(r.stylus_force.allFinite());
  REQUIRE(r.stylus_force.norm() <= s.max_stylus_force + 1e-12);
  // The state the loop used is plausible.
  for (int i = 0; i < 4; ++i) {
    REQUIRE(std::fabs(r.measured.position[i]) <= 1.028 + s.plausibility.position_margin);
    REQUIRE(std::fabs(r.measured.velocity[i]) <= s.plausibility.max_velocity);
    REQUIRE(std::fabs(r.measured.current[i]) <= s.plausibility.max_current);
  }
  // Enabled motors move at most the rate limit per tick: from the previous setpoint, or after a
  // recovery from where a released joint was measured (the robot is there, not at the old
  // setpoint; docs/safety.md).
  if (r.enable_mask != 0 && previous.enable_mask != 0) {
    for (int j = 0; j < 4; ++j) {
      const bool released = ((previous.measured.active_mask >> j) & 1u) == 0;
      const double from = recovered && released ? std::clamp(previous.measured.position[j],
                                                             s.joint_lower[j], s.joint_upper[j])
                                                : previous.setpoint[j];
      REQUIRE(std::fabs(r.setpoint[j] - from) <= s.max_setpoint_rate * 1e-3 + 1e-12);
    }
  }
  // A fault is reported and takes the link down (or keeps it waiting), never "ok".
  if (r.state_fault != tp::StateFault::none) {
    REQUIRE(r.status == tp::TickStatus::state_fault);
    REQUIRE((r.link == tp::LinkState::lost || r.link == tp::LinkState::waiting));
    REQUIRE(r.stylus_force.norm() == 0.0);
  }
}

}  // namespace

TEST_CASE("a first state of 50 rad is a fault: nothing enabled, setpoints stay in range") {
  // Before: setpoints 49.996 rad, then 46 rad after 1 s, enable mask 15 (the rate limiter started
  // from the reported position and nothing held the result to the joint range).
  Rig rig;
  rig.link.responder().fixed = Answer::huge_position;
  for (int i = 0; i < 2000; ++i) {
    const auto r = rig.tick();
    REQUIRE(r.status == tp::TickStatus::state_fault);
    REQUIRE(r.state_fault == tp::StateFault::position_out_of_range);
    REQUIRE(r.enable_mask == 0);
    REQUIRE(r.setpoint.cwiseAbs().maxCoeff() <= 1.028);
    REQUIRE(r.link == tp::LinkState::waiting);
  }
  const auto& stats = rig.loop.stats();
  CHECK(stats.state_faults() == 2000);
  CHECK(stats.state_faults(tp::StateFault::position_out_of_range) == 2000);
  CHECK(stats.received() == 0);
  CHECK(stats.loss_percent() == 100.0);
}

TEST_CASE("a state of +-3e38 everywhere is a fault, never a setpoint") {
  Rig rig;
  rig.link.responder().fixed = Answer::float_max;
  for (int i = 0; i < 100; ++i) {
    const auto r = rig.tick();
    REQUIRE(r.state_fault == tp::StateFault::position_out_of_range);
    REQUIRE(r.setpoint.cwiseAbs().maxCoeff() <= 1.028);
    REQUIRE(r.enable_mask == 0);
  }
}

TEST_CASE("each implausible state after contact: fault, counted by cause, safe state at once") {
  struct Case {
    Answer answer;
    tp::StateFault fault;
  };
  const Case cases[] = {
      {Answer::huge_position, tp::StateFault::position_out_of_range},
      {Answer::position_edge, tp::StateFault::position_out_of_range},
      {Answer::fast, tp::StateFault::velocity_out_of_range},
      {Answer::overcurrent, tp::StateFault::current_out_of_range},
      {Answer::jump, tp::StateFault::position_jump},
  };
  for (const auto policy : {tp::SafeStatePolicy::hold_position, tp::SafeStatePolicy::disable_motors,
                            tp::SafeStatePolicy::zero_force}) {
    for (const auto& c : cases) {
      CAPTURE(static_cast<int>(c.answer));
      CAPTURE(tp::to_string(policy));
      tp::TeleopLoopConfig config;
      config.safety.policy = policy;
      Rig rig(config);
      rig.link.responder().fixed = Answer::honest;
      tp::TickResult r;
      for (int i = 0; i < 700; ++i) r = rig.tick();
      REQUIRE(r.status == tp::TickStatus::ok);
      const auto measured = r.measured;
      const auto held = r.setpoint;

      rig.link.responder().fixed = c.answer;
      r = rig.tick();
      CHECK(r.status == tp::TickStatus::state_fault);
      CHECK(r.state_fault == c.fault);
      CHECK(r.link == tp::LinkState::lost);
      CHECK(r.measured == measured);  // never followed
      CHECK(r.stylus_force.norm() == 0.0);
      CHECK(rig.loop.stats().state_faults(c.fault) == 1);
      CHECK(rig.loop.watchdog().link_losses() == 1);

      // The next setpoint obeys the safe-state policy.
      r = rig.tick();
      switch (policy) {
        case tp::SafeStatePolicy::hold_position:
          CHECK(r.enable_mask == 0x0F);
          CHECK((r.setpoint - held).cwiseAbs().maxCoeff() <= 4.0 * 1e-3 + 1e-12);
          break;
        case tp::SafeStatePolicy::disable_motors:
          CHECK(r.enable_mask == 0);
          break;
        case tp::SafeStatePolicy::zero_force:
          CHECK(r.enable_mask == 0x0F);
          break;
      }
      CHECK(r.stylus_force.norm() == 0.0);

      // Honest states again: recovery with the force ramp, as after any loss.
      rig.link.responder().fixed = Answer::honest;
      for (int i = 0; i < 5; ++i) r = rig.tick();
      CHECK(r.link == tp::LinkState::recovering);
      CHECK(r.force_scale < 0.02);
    }
  }
}

TEST_CASE("junk after the newest valid state cannot displace it, rejections counted by cause") {
  Rig rig;
  rig.link.responder().fixed = Answer::flood;
  tp::TickResult r;
  for (int i = 0; i < 100; ++i) {
    r = rig.tick();
    REQUIRE(r.exchange == tp::TickOutcome::received);
    REQUIRE(r.rejected.wrong_size == 20);
  }
  CHECK(rig.loop.stats().received() == 100);
  CHECK(rig.loop.stats().rejected().wrong_size == 2000);
  CHECK(rig.loop.stats().loss_percent() == 0.0);

  rig.link.responder().fixed = Answer::nan_bits;
  r = rig.tick();
  CHECK(r.exchange == tp::TickOutcome::decode_error);
  CHECK(r.decode == endohaptics::protocol::CodecStatus::non_finite);
  CHECK(r.rejected.non_finite == 1);
  rig.link.responder().fixed = Answer::bad_mask;
  r = rig.tick();
  CHECK(r.decode == endohaptics::protocol::CodecStatus::mask_out_of_range);
  CHECK(rig.loop.stats().rejected().bad_mask == 1);
}

TEST_CASE("property: random and adversarial state streams never open the envelope") {
  // 12 seeds x 3 policies x 3000 ticks; half the answers honest (so the link comes up and the
  // limits are exercised while enabled), half drawn from every attack above.
  for (const auto policy : {tp::SafeStatePolicy::hold_position, tp::SafeStatePolicy::disable_motors,
                            tp::SafeStatePolicy::zero_force}) {
    for (std::uint64_t seed = 1; seed <= 12; ++seed) {
      CAPTURE(seed);
      CAPTURE(tp::to_string(policy));
      tp::TeleopLoopConfig config;
      config.safety.policy = policy;
      Rig rig(config);
      rig.link.responder().rng.seed(seed);
      rig.link.responder().honest_percent = seed % 3 == 0 ? 90 : 50;
      rig.device.rng.seed(seed + 100);
      tp::TickResult previous;
      bool recovered = false;
      previous.enable_mask = 0;
      std::uint64_t faults = 0;
      std::uint64_t enabled = 0;
      for (int i = 0; i < 3000; ++i) {
        const auto r = rig.tick();
        check_envelope(r, previous, config, recovered);
        recovered = previous.link == tp::LinkState::lost && r.link == tp::LinkState::recovering;
        faults += r.state_fault != tp::StateFault::none;
        enabled += r.enable_mask != 0;
        previous = r;
      }
      CHECK(faults == rig.loop.stats().state_faults());
      CHECK(faults > 0);
      CHECK(enabled > 0);  // the envelope was tested with motors enabled too
    }
  }
}

TEST_CASE("property: with the passivity layer on (TDPA), the envelope stays closed too") {
  // The TDPA's robot-side controller rewrites the setpoint and its operator-side controller the
  // force: neither may step outside the range, the rate limit or the force limit. Round trips of
  // 0 and 20 ticks, a finite and an unlimited joint force limit; 6 seeds x 3 policies each.
  for (const int round_trip : {0, 20}) {
    for (const bool limited : {false, true}) {
      for (const auto policy :
           {tp::SafeStatePolicy::hold_position, tp::SafeStatePolicy::disable_motors,
            tp::SafeStatePolicy::zero_force}) {
        for (std::uint64_t seed = 1; seed <= 6; ++seed) {
          CAPTURE(round_trip);
          CAPTURE(limited);
          CAPTURE(seed);
          CAPTURE(tp::to_string(policy));
          tp::TeleopLoopConfig config;
          config.safety.policy = policy;
          config.passivity.mode = tp::PassivityMode::tdpa;
          config.passivity.round_trip_ticks = round_trip;
          if (limited) config.passivity.force_limit.setConstant(2.0);
          Rig rig(config);
          rig.link.responder().rng.seed(seed);
          rig.link.responder().honest_percent = seed % 3 == 0 ? 90 : 60;
          rig.device.rng.seed(seed + 200);
          tp::TickResult previous;
          previous.enable_mask = 0;
          bool recovered = false;
          std::uint64_t robot_active = 0, operator_active = 0, enabled = 0;
          for (int i = 0; i < 3000; ++i) {
            const auto r = rig.tick();
            check_envelope(r, previous, config, recovered);
            recovered = previous.link == tp::LinkState::lost && r.link == tp::LinkState::recovering;
            robot_active += r.passivity.robot_active;
            operator_active += r.passivity.operator_active;
            enabled += r.enable_mask != 0;
            previous = r;
          }
          CHECK(enabled > 0);
          // The controllers acted in these runs (the loud estimator's forces do work).
          CHECK(robot_active + operator_active > 0);
        }
      }
    }
  }
}

TEST_CASE("property: uniformly random state bytes never open the envelope") {
  // Every float of every state drawn from all 2^32 bit patterns (NaN, Inf, denormals, 3e38...).
  transport::RespondingTransport<RandomBytes, 64, 32> link{RandomBytes{}};
  WildDevice device;
  LoudEstimator estimator;
  Mapper mapper;
  endohaptics::ManualClock clock{1s};
  tp::TeleopLoopConfig config;
  tp::TeleopLoop loop(link, device, estimator, mapper, clock, config);
  tp::TickResult previous;
  bool recovered = false;
  for (int i = 0; i < 20000; ++i) {
    const auto r = loop.tick();
    clock.advance(1ms);
    check_envelope(r, previous, config, recovered);
    recovered = previous.link == tp::LinkState::lost && r.link == tp::LinkState::recovering;
    previous = r;
  }
  // About half of all bit patterns are NaN/Inf-free floats; few states are plausible as a whole.
  CHECK(loop.stats().state_faults() > 10000);
  CHECK(loop.stats().received() < 100);
}

TEST_CASE("the hostile stream costs no heap allocation") {
  Rig rig;
  for (int i = 0; i < 100; ++i) (void)rig.tick();
  const long allocations = allocations_during([&] {
    for (int i = 0; i < 5000; ++i) (void)rig.tick();
  });
  CHECK(allocations == 0);
}

TEST_CASE("safety configuration: physical bounds, with the field and range in the message") {
  auto message = [](auto mutate) {
    tp::TeleopLoopConfig config;
    mutate(config);
    try {
      config.validate();
    } catch (const endohaptics::Error& e) {
      return std::string(e.what());
    }
    return std::string("accepted");
  };
  using C = tp::TeleopLoopConfig;
  CHECK(message([](C&) {}) == "accepted");
  CHECK(message([](C& c) { c.safety.max_consecutive_misses = 2147483647; }) ==
        "SafetyConfig: max_consecutive_misses must be in [0, 1000], got 2147483647");
  CHECK(message([](C& c) { c.safety.max_stylus_force = 1e308; }) ==
        "SafetyConfig: max_stylus_force must be in [0, 3.3] N (the Touch's peak), got 1e+308");
  CHECK(message([](C& c) {
          c.safety.max_setpoint_rate = std::numeric_limits<double>::infinity();
        }).starts_with("SafetyConfig: max_setpoint_rate must be in (0, 40] rad/s"));
  CHECK(message([](C& c) {
          c.safety.force_ramp_time = -0.9;
        }).starts_with("SafetyConfig: force_ramp_time must be in [0, 10] s"));
  CHECK(message([](C& c) {
          c.safety.joint_lower[2] = 0.5;
          c.safety.joint_upper[2] = 0.5;
        }) == "SafetyConfig: joint_upper[2] must be above joint_lower[2], got 0.5");
  CHECK(message([](C& c) { c.safety.joint_upper[0] = 4.0; }) ==
        "SafetyConfig: joint_upper[0] must be in [-pi, pi] rad, got 4");
  CHECK(message([](C& c) { c.safety.plausibility.max_current = 100.0; }) ==
        "StatePlausibility: max_current must be in (0, 15] A, got 100");
  CHECK(message([](C& c) {
          c.safety.plausibility.max_velocity = std::nan("");
        }).starts_with("StatePlausibility: max_velocity must be in (0, 40] rad/s"));
  // The watchdog must declare a silent link lost within 0.5 s.
  CHECK(message([](C& c) { c.safety.max_consecutive_misses = 499; }) == "accepted");  // 0.5 s
  CHECK(message([](C& c) { c.safety.max_consecutive_misses = 500; })
            .starts_with("TeleopLoopConfig: (safety.max_consecutive_misses + 1) x max(period, "
                         "receive_timeout) = 501 x 1000000 ns must be <= 500000000 ns"));
  CHECK(message([](C& c) { c.period = 100ms; }).find("11 x 100000000 ns") != std::string::npos);
  CHECK(message([](C& c) {
          c.receive_timeout = 1s;
        }).starts_with("TeleopLoopConfig: receive_timeout must be in (0, 0.5] s, got 1"));
  CHECK(message([](C& c) {
          c.receive_timeout = 0s;
        }).starts_with("TeleopLoopConfig: receive_timeout must be in (0, 0.5] s, got 0"));
}

TEST_CASE(
    "after a loss with the motors released, the first enabled setpoint starts where the "
    "robot is") {
  // Review finding: the limiter was re-seeded on first contact only, so after disable_motors (or
  // the sbRIO's own watchdog) let the robot drift, re-enabling jumped back to the old setpoint.
  tp::TeleopLoopConfig config;
  config.safety.policy = tp::SafeStatePolicy::disable_motors;
  Rig rig(config);
  auto& sbrio = rig.link.responder();
  sbrio.fixed = Answer::honest;
  tp::TickResult r;
  for (int i = 0; i < 700; ++i) r = rig.tick();
  REQUIRE(r.status == tp::TickStatus::ok);
  sbrio.fixed = Answer::silent;
  for (int i = 0; i < 300; ++i) r = rig.tick();
  REQUIRE(r.link == tp::LinkState::lost);
  REQUIRE(r.enable_mask == 0);
  sbrio.truth.position[1] = 0.8;  // released, the pitch sagged meanwhile
  sbrio.fixed = Answer::honest;
  r = rig.tick();  // the first answer: recovering, still disabled this tick
  REQUIRE(r.link == tp::LinkState::recovering);
  r = rig.tick();
  REQUIRE(r.enable_mask != 0);
  CHECK(std::fabs(r.setpoint[1] - 0.8) <= 4.0 * 1e-3 + 1e-9);
}

namespace {

// A stylus that stays where the test puts it.
struct PlacedDevice {
  Eigen::Vector3d position{0.13, 0.0, 0.137};
  Eigen::Vector3d force = Eigen::Vector3d::Zero();
  tp::DeviceStatus read(tp::StylusSample& s) noexcept {
    s.position = position;
    return tp::DeviceStatus::ok;
  }
  tp::DeviceStatus command_force(const Eigen::Vector3d& f) noexcept {
    force = f;
    return tp::DeviceStatus::ok;
  }
};

}  // namespace

TEST_CASE("a stylus beyond the joint range does not park the setpoint at the edge") {
  // Review finding: the limiter chased the unclamped desired setpoint, so with a mapper range
  // wider than the safety range the sent setpoint stuck at the edge on the way back (332 ms).
  Link link{HostileSbrio{}};
  link.responder().fixed = Answer::honest;
  PlacedDevice device;
  LoudEstimator estimator;
  endohaptics::kinematics::CylindricalMapperConfig<double> wide;
  wide.lower.setConstant(-3.0);
  wide.upper.setConstant(3.0);
  Mapper mapper(wide);
  endohaptics::ManualClock clock{1s};
  tp::TeleopLoop loop(link, device, estimator, mapper, clock, tp::TeleopLoopConfig{});
  auto tick = [&] {
    const auto r = loop.tick();
    clock.advance(1ms);
    return r;
  };
  tp::TickResult r;
  for (int i = 0; i < 100; ++i) r = tick();
  device.position.z() += 0.6;  // desired pitch 2.5 rad: beyond the safety range
  for (int i = 0; i < 1000; ++i) r = tick();
  REQUIRE(r.setpoint[1] == doctest::Approx(1.028));
  device.position.z() -= 0.6;  // back to the middle: the setpoint leaves the edge at once
  r = tick();
  CHECK(r.setpoint[1] < 1.028 - 0.003);
}

TEST_CASE("a period so long that the watchdog product would overflow is refused") {
  tp::TeleopLoopConfig config;
  config.period = std::chrono::nanoseconds(std::int64_t{1} << 62);
  CHECK_THROWS_AS(config.validate(), endohaptics::Error);
}

TEST_CASE("a channel clipped by the mapper counts as a limited force") {
  // Review finding: with the default channel limits (1.4 N each) neither the magnitude limit nor
  // the loop's guard could fire, so a clipped estimate was reported as not limited.
  struct PitchEstimator {  // a spurious 10 N on pitch (the worksheet saw ~10 N there)
    bool estimate(const tp::MotorState4&, const tp::MotorVector&, tp::MotorVector& f) noexcept {
      f = tp::MotorVector(0.0, 10.0, 0.0, 0.0);
      return true;
    }
    void reset() noexcept {}
  };
  Link link{HostileSbrio{}};
  link.responder().fixed = Answer::honest;
  PlacedDevice device;
  PitchEstimator estimator;
  Mapper mapper;
  endohaptics::ManualClock clock{1s};
  tp::TeleopLoop loop(link, device, estimator, mapper, clock, tp::TeleopLoopConfig{});
  tp::TickResult r;
  for (int i = 0; i < 1000; ++i) {
    r = loop.tick();
    clock.advance(1ms);
  }
  REQUIRE(r.status == tp::TickStatus::ok);
  CHECK(std::fabs(r.stylus_force.z()) == doctest::Approx(1.4));  // the pitch channel's limit
  CHECK(r.force_limited);
}

}  // namespace teleop_safety_envelope_test
