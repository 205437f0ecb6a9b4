// The closed loop with the operator in it (sim::ClosedLoop): the arm of table 5.1 presses clamp 1
// into a contact through the real TeleopLoop over a delayed, lossy network and holds. The sweep
// of docs/passivity.md: round trip {0, 20, 50, 100, 200} ms x loss {0, 10 %} x {soft tissue, stiff
// stop}, without passivity (the observer only: the loop renders exactly what it would with it off)
// and with TDPA. docs/passivity.md prints the same table (endohaptics-passivity-sweep --table).
// With the sensorless estimate too: a clamp model identified on training runs (force feedback
// off, other presses than the sweep's), as endohaptics-passivity-sweep --force-source identified
// does.
#include "alloc_counter.hpp"  // first: counts every heap allocation of this executable

#include <doctest/doctest.h>

#include <array>
#include <chrono>
#include <endohaptics/estimation/stiction_hold.hpp>
#include <endohaptics/sim/closed_loop.hpp>
#include <endohaptics/sim/passivity_sweep.hpp>
#include <filesystem>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include <unistd.h>

#include "../../examples/passivity_sweep/identify_training.hpp"

namespace sim_passivity_sweep_test {

namespace {

namespace sim = endohaptics::sim;
namespace tp = endohaptics::teleop;
using endohaptics::test::allocations_during;

// The sweep's scenarios, run length and criteria: sim/passivity_sweep.hpp (the program's too).
constexpr double seconds_without = sim::press_seconds_without;
constexpr double seconds_with = sim::press_seconds_with;
constexpr double epsilon = sim::PressCriteria{}.epsilon;
constexpr double max_drift = sim::PressCriteria{}.max_drift;
sim::ClosedLoopConfig scenario(int ms, double loss, sim::ContactKind contact,
                               tp::PassivityMode mode,
                               sim::ForceSource source = sim::ForceSource::sensor,
                               const std::optional<sim::IdentifiedClamp>& clamp = std::nullopt) {
  return sim::press_scenario(ms, loss, contact, mode, source, clamp);
}

sim::PressReport run(const sim::ClosedLoopConfig& config, double seconds) {
  return sim::run_press(config, seconds);
}

std::string name(int ms, double loss, sim::ContactKind contact) {
  return std::to_string(ms) + " ms, loss " + std::to_string(static_cast<int>(loss * 100)) + " %, " +
         std::string(to_string(contact));
}

// Every setting of one round trip: with TDPA stable and passive; without, what it is.
void check_row(int ms) {
  for (const double loss : {0.0, 0.1}) {
    for (const auto contact : {sim::ContactKind::soft_tissue, sim::ContactKind::stiff_stop}) {
      CAPTURE(name(ms, loss, contact));
      const sim::PressReport with =
          run(scenario(ms, loss, contact, tp::PassivityMode::tdpa), seconds_with);
      REQUIRE(with.contact);
      CHECK(with.min_energy > -epsilon);
      CHECK(with.decays());
      CHECK(with.drift < max_drift);
      CHECK(with.max_force < 3.0);   // never at the loop's 3 N limit
      CHECK(with.hold_force > 0.4);  // and the contact is still felt
      CHECK(sim::press_meets_criteria(with, ms));
    }
  }
}

// The clamp model identified on the training runs, with its free-motion error bound measured
// there, once per test process (its own directory: CTest runs test cases in parallel processes).
const sim::IdentifiedClamp& identified_clamp() {
  static const sim::IdentifiedClamp clamp = [] {
    const auto dir = std::filesystem::temp_directory_path() /
                     ("endohaptics-sweep-test-" + std::to_string(::getpid()));
    auto m = sweep_identify::identify_sweep_clamp_model(dir);
    std::filesystem::remove_all(dir);
    return sim::identified_clamp(std::move(m));
  }();
  return clamp;
}
const endohaptics::estimation::BridgeJointModel& identified_model() {
  return identified_clamp().model;
}

// One case of the sweep with the identified model and TDPA.
sim::PressReport identified_with_tdpa(int ms, double loss, sim::ContactKind contact) {
  return run(scenario(ms, loss, contact, tp::PassivityMode::tdpa, sim::ForceSource::identified,
                      identified_clamp()),
             seconds_with);
}

// Every setting of one round trip with the identified model and TDPA: every criterion of the
// sweep, the felt / true hold force included up to 100 ms.
void check_identified_row(int ms) {
  for (const double loss : {0.0, 0.1}) {
    for (const auto contact : {sim::ContactKind::soft_tissue, sim::ContactKind::stiff_stop}) {
      CAPTURE(name(ms, loss, contact));
      const sim::PressReport r = identified_with_tdpa(ms, loss, contact);
      CAPTURE(r.felt_ratio());
      CAPTURE(r.decay_amplitude);
      CAPTURE(r.hold_force);
      CHECK(sim::press_missed_criteria(r, ms) == "");
      CHECK(sim::press_meets_criteria(r, ms));
    }
  }
}

}  // namespace

TEST_CASE("passivity sweep: 100 ms stiff stop is unstable without passivity") {
  for (const double loss : {0.0, 0.1}) {
    CAPTURE(loss);
    const sim::PressReport without =
        run(scenario(100, loss, sim::ContactKind::stiff_stop, tp::PassivityMode::observe),
            seconds_without);
    REQUIRE(without.contact);
    CHECK_FALSE(without.decays());              // the oscillation does not decay
    CHECK(without.min_energy < -10 * epsilon);  // the channel generated energy
    CHECK(without.max_force >= 3.0 - 1e-9);     // the force reached the loop's limit
    CHECK(sim::press_verdict_without(without) ==
          "UNSTABLE (no decay, energy generated, force limit)");
    CHECK_FALSE(sim::press_meets_criteria(without, 100));
  }
}

TEST_CASE(
    "passivity sweep: without passivity, low delays and soft tissue up to 100 ms stay stable") {
  // The other side of the table: the unstable settings are the stiff stop from 50 ms and soft
  // tissue at 200 ms (docs/passivity.md); these stay stable, so the instability above is delay's.
  for (const int ms : {0, 20}) {
    for (const auto contact : {sim::ContactKind::soft_tissue, sim::ContactKind::stiff_stop}) {
      CAPTURE(name(ms, 0.0, contact));
      const sim::PressReport r =
          run(scenario(ms, 0.0, contact, tp::PassivityMode::observe), seconds_without);
      CHECK(r.decays());
      CHECK(sim::press_verdict_without(r).starts_with("stable") ==
            (r.min_energy >= -epsilon && r.max_force < 3.0 - 1e-9));
    }
  }
  const sim::PressReport soft200 =
      run(scenario(200, 0.0, sim::ContactKind::soft_tissue, tp::PassivityMode::observe),
          seconds_without);
  CHECK_FALSE(soft200.decays());
}

TEST_CASE("passivity sweep: 0 ms round trip, TDPA stable at every loss and contact") {
  check_row(0);
}
TEST_CASE("passivity sweep: 20 ms round trip, TDPA stable at every loss and contact") {
  check_row(20);
}
TEST_CASE("passivity sweep: 50 ms round trip, TDPA stable at every loss and contact") {
  check_row(50);
}
TEST_CASE("passivity sweep: 100 ms round trip, TDPA stable at every loss and contact") {
  check_row(100);
}
TEST_CASE("passivity sweep: 200 ms round trip, TDPA stable at every loss and contact") {
  check_row(200);
}

// The sensorless estimate (docs/passivity.md, "With the sensorless estimate"): a clamp model
// identified on the training presses, the current through a play of the clamp's static friction.
// With TDPA every case meets every criterion, the hold felt (felt / true >= 0.5) up to 100 ms;
// without TDPA the identified loop is stable at the stiff stop at 20 ms and unstable from 50 ms.
// One test case with a subcase per round trip: the model is identified once per process (3.3 s
// of the sanitized build's CPU, most of each case's time; five cases identified it five times).
TEST_CASE("passivity sweep: identified with TDPA, every round trip, every criterion") {
  SUBCASE("0 and 20 ms") {
    for (const int ms : {0, 20}) check_identified_row(ms);
    const sim::PressReport without =
        run(scenario(20, 0.0, sim::ContactKind::stiff_stop, tp::PassivityMode::observe,
                     sim::ForceSource::identified, identified_clamp()),
            seconds_without);
    CHECK(sim::press_stable_without(without));
  }
  SUBCASE("50 ms") {
    check_identified_row(50);
    const sim::PressReport without =
        run(scenario(50, 0.0, sim::ContactKind::stiff_stop, tp::PassivityMode::observe,
                     sim::ForceSource::identified, identified_clamp()),
            seconds_without);
    CHECK_FALSE(sim::press_stable_without(without));
  }
  SUBCASE("100 ms") { check_identified_row(100); }
  SUBCASE("200 ms") { check_identified_row(200); }
  // Last: its REQUIRE would end the test case before the round trips' subcases.
  SUBCASE("the identified model's current play is the clamp's static friction") {
    // K_s of the simulated clamp in the current domain (docs/models/sim.md: clamp 1 0.21 A), the
    // demo's play for the emulator's clamp 1 (examples/demo.sh); the request the sweep identifies
    // with is the demo's for pitch and the clamps.
    CHECK(sim::clamp_current_play() == doctest::Approx(0.21));
    const auto r = sweep_identify::training_request({"a.csv"});
    CHECK(r.current_play == sim::clamp_current_play());
    CHECK(r.order == "auto");
    CHECK(r.max_order == 4);
    CHECK(r.deadzone == "0,auto");
    // The model identified so: its play and its free-motion error bound on the training presses,
    // the tolerance the sweep's scenarios use.
    const auto* hw =
        identified_model().get<endohaptics::estimation::IdentifiedHammersteinWiener<double>>();
    REQUIRE(hw != nullptr);
    CHECK(hw->current_play() == sim::clamp_current_play());
    // Measured on the training presses (0.014 N when the sweep's table was recorded): within the
    // stylus's free-motion goal of 0.05 N, and the bound the scenarios carry.
    CHECK(identified_clamp().free_motion_error > 0.0);
    CHECK(identified_clamp().free_motion_error < 0.05);
  }
}

// What the play replaces: the model with a current dead zone (order 2, as before the play) reads
// the unloading branch as 0, and even with the through-zero stiction hold round 1 added it misses
// the felt / true force at the 50 ms stiff stop and does not decay at 100 ms (docs/passivity.md):
// marked should_fail, so it reports should that model ever meet every criterion there.
TEST_CASE("passivity sweep: identified with a current dead zone, 50 and 100 ms (not met)" *
          doctest::should_fail()) {
  const auto dir = std::filesystem::temp_directory_path() /
                   ("endohaptics-sweep-test-dz-" + std::to_string(::getpid()));
  const auto model =
      sweep_identify::identify_sweep_clamp_model(dir, sweep_identify::TrainingFit::deadzone);
  std::filesystem::remove_all(dir);
  const sim::IdentifiedClamp clamp = sim::identified_clamp(model);  // its bound: 0.088 N
  for (const int ms : {50, 100}) {
    for (const auto contact : {sim::ContactKind::soft_tissue, sim::ContactKind::stiff_stop}) {
      CAPTURE(name(ms, 0.0, contact));
      auto c =
          scenario(ms, 0.0, contact, tp::PassivityMode::tdpa, sim::ForceSource::identified, clamp);
      c.stiction_memory = true;
      c.stiction_through_zero = true;
      for (const int j : {2, 3}) {
        c.stiction_contact_level[j] = clamp.free_motion_error;
        c.passivity.robot_cost_tolerance[j] = clamp.free_motion_error;
      }
      const sim::PressReport r = run(c, seconds_with);
      CHECK(sim::press_missed_criteria(r, ms) == "");
    }
  }
}

TEST_CASE("passivity closed loop: the stiction memory's settings are the instrument's constants") {
  // The demo's numbers for the emulator's instrument (examples/demo.sh: 2 K_s k_tau N / k_t,
  // the play, K_s k_tau N / lever), here derived from the simulated rig's parameters.
  endohaptics::estimation::ForceEstimatorSettings<double> s;
  sim::stiction_memory_settings(sim::endowrist_2016_rig<4>(), s);
  const std::array<double, 4> travel{0.0330, 0.0432, 0.0314, 0.0299};
  const std::array<double, 4> force{0.458, 0.599, 0.416, 0.397};
  for (int j = 0; j < 4; ++j) {
    CAPTURE(j);
    CHECK(s.stick_travel[j] == doctest::Approx(travel[static_cast<std::size_t>(j)]).epsilon(2e-3));
    CHECK(s.stick_play[j] == doctest::Approx(0.01745));
    CHECK(s.stick_force[j] == doctest::Approx(force[static_cast<std::size_t>(j)]).epsilon(2e-3));
  }
  // The identified source runs none (its model's current play holds the static-friction band),
  // the model's free-motion error bound as the robot-side controller's tolerance (and the hold's
  // contact level, should it be switched on); the 2016 preset no memory either.
  // (any clamp model: only the configuration is looked at)
  const sim::IdentifiedClamp clamp{
      endohaptics::estimation::bridge_force_models(std::nullopt).clamp1, 0.014};
  const auto identified = scenario(0, 0.0, sim::ContactKind::soft_tissue, tp::PassivityMode::tdpa,
                                   sim::ForceSource::identified, clamp);
  CHECK_FALSE(identified.stiction_memory);
  CHECK(identified.stiction_contact_level[2] == 0.014);
  CHECK(identified.passivity.robot_cost_tolerance[2] == 0.014);
  CHECK(identified.passivity.robot_cost_tolerance[0] == 0.0);
  CHECK_FALSE(scenario(0, 0.0, sim::ContactKind::soft_tissue, tp::PassivityMode::tdpa,
                       sim::ForceSource::preset_2016)
                  .stiction_memory);
}

TEST_CASE("passivity closed loop: the stiction hold keeps a stuck joint's force through zero") {
  // Clamp 1 as in the 100 ms stiff case of docs/passivity.md: held -0.76 N (the external force
  // along -setpoint, so the motor pressed along +), the motor backs off along -.
  endohaptics::estimation::ForceEstimatorSettings<double> s;
  s.stick_travel[2] = 0.0314;
  s.stick_play[2] = 0.01745;
  s.stick_force[2] = 0.416;
  const endohaptics::estimation::StictionHold<>::Vector level(0.0, 0.0, 0.05, 0.05);
  endohaptics::estimation::StictionHold<> hold(s, level);
  CHECK(hold.apply(2, -0.76, 0.198) == -0.76);
  CHECK(hold.apply(2, -0.40, 0.190) == -0.76);  // fell, backed off 8 mrad: held
  CHECK(hold.apply(2, 0.016, 0.173) == -0.76);  // the other side, 25 mrad: still held
  CHECK(hold.apply(2, 0.016, 0.160) == 0.016);  // 38 mrad, beyond the stuck travel: let go
  CHECK(hold.apply(0, 0.5, 0.0) == 0.5);        // roll: no memory configured, passed on
  CHECK(hold.apply(2, -0.30, 0.170) == -0.30);  // a press: 0.016 N is no contact, not held
  CHECK(hold.apply(2, -0.10, 0.175) == -0.10);  // a fall with the motor not backed off: followed
  CHECK(hold.apply(2, -0.30, 0.180) == -0.30);  // pressed on
  CHECK(hold.apply(2, -0.20, 0.160) == -0.30);  // below stick_force the play is added:
  CHECK(hold.apply(2, -0.20, 0.140) == -0.30);  // 40 mrad < 31.4 + 17.5 mrad: held
  CHECK(hold.apply(2, -0.20, 0.130) == -0.20);  // 50 mrad: let go
  // With a contact level of 0 the same 0.016 N would be held against the press.
  endohaptics::estimation::StictionHold<> noisy(
      s, endohaptics::estimation::StictionHold<>::Vector::Zero());
  CHECK(noisy.apply(2, -0.76, 0.198) == -0.76);
  CHECK(noisy.apply(2, 0.016, 0.160) == 0.016);
  CHECK(noisy.apply(2, -0.30, 0.170) == 0.016);
  // Without one (ForceEstimator's rule) only a fall on the same side is held.
  endohaptics::estimation::StictionHold<> same_side(s);
  CHECK(same_side.apply(2, -0.76, 0.198) == -0.76);
  CHECK(same_side.apply(2, -0.40, 0.190) == -0.76);
  CHECK(same_side.apply(2, 0.016, 0.173) == 0.016);
  s.stick_play[1] = -1.0;
  CHECK_THROWS_WITH_AS(endohaptics::estimation::StictionHold<>{s},
                       doctest::Contains("stick_play[1]"), endohaptics::Error);
}

TEST_CASE("passivity closed loop: the preset-2016 estimate runs from the sbRIO's reports only") {
  // The estimator sees the decoded state: zero contact, zero force held; the sensor's tag is
  // never read (a scenario with the sensor source and one with the preset differ).
  auto preset = std::make_unique<sim::ClosedLoop>(scenario(0, 0.0, sim::ContactKind::stiff_stop,
                                                           tp::PassivityMode::observe,
                                                           sim::ForceSource::preset_2016));
  auto sensor = std::make_unique<sim::ClosedLoop>(
      scenario(0, 0.0, sim::ContactKind::stiff_stop, tp::PassivityMode::observe));
  bool differ = false;
  for (int i = 0; i < 2000; ++i) {
    const auto a = preset->step();
    const auto b = sensor->step();
    differ = differ || a.estimated_force != b.estimated_force;
  }
  CHECK(differ);
  sim::ClosedLoopConfig c;
  c.force_source = sim::ForceSource::identified;  // without a model
  CHECK_THROWS_WITH(sim::ClosedLoop{c}, doctest::Contains("identified needs a clamp_model"));
  CHECK_THROWS_WITH((void)scenario(0, 0.0, sim::ContactKind::stiff_stop, tp::PassivityMode::tdpa,
                                   sim::ForceSource::identified),
                    doctest::Contains("needs its clamp model"));
}

TEST_CASE("passivity closed loop: observe renders exactly what off renders") {
  auto off = std::make_unique<sim::ClosedLoop>(
      scenario(100, 0.1, sim::ContactKind::stiff_stop, tp::PassivityMode::off));
  auto observe = std::make_unique<sim::ClosedLoop>(
      scenario(100, 0.1, sim::ContactKind::stiff_stop, tp::PassivityMode::observe));
  bool same = true, energy_seen = false;
  for (int i = 0; i < 2500; ++i) {
    const sim::ClosedLoopSample a = off->step();
    const sim::ClosedLoopSample b = observe->step();
    same = same && a.stylus_force == b.stylus_force && a.setpoint == b.setpoint;
    energy_seen = energy_seen || b.passivity.energy != 0.0;
    CHECK(a.passivity.energy == 0.0);
  }
  CHECK(same);
  CHECK(energy_seen);
}

TEST_CASE("passivity closed loop: a step with TDPA allocates nothing, and is deterministic") {
  sim::ClosedLoopConfig config =
      scenario(50, 0.1, sim::ContactKind::stiff_stop, tp::PassivityMode::tdpa);
  SUBCASE("ideal sensor") {}
  SUBCASE("the 2016 preset's estimate, per-direction observers") {
    config = scenario(50, 0.1, sim::ContactKind::stiff_stop, tp::PassivityMode::tdpa,
                      sim::ForceSource::preset_2016);
  }
  auto a = std::make_unique<sim::ClosedLoop>(config);
  auto b = std::make_unique<sim::ClosedLoop>(config);
  double last_a = 0.0, last_b = 0.0;
  const long n = allocations_during([&] {
    for (int i = 0; i < 3000; ++i) last_a = a->step().stylus_force;
  });
  CHECK(n == 0);
  for (int i = 0; i < 3000; ++i) last_b = b->step().stylus_force;
  CHECK(last_a == last_b);
  CHECK(a->loop().stats().passivity().ticks > 0);
}

TEST_CASE("passivity closed loop: a bad scenario is refused with its field") {
  sim::ClosedLoopConfig c;
  c.loss = 1.5;
  CHECK_THROWS_WITH(sim::ClosedLoop{c}, doctest::Contains("loss must be in [0, 1], got 1.5"));
  c = {};
  c.round_trip = std::chrono::seconds(30);
  CHECK_THROWS_WITH(sim::ClosedLoop{c}, doctest::Contains("DelaySettings"));
  c = {};
  c.press_depth = 1.0;
  CHECK_THROWS_WITH(sim::ClosedLoop{c}, doctest::Contains("press_depth"));
}

TEST_CASE("passivity: DelayedSendTransport holds each send for the delay and loses at its rate") {
  using endohaptics::ManualClock;
  using Inner = endohaptics::transport::InMemoryTransport<>;
  Inner::Queue tx, rx;
  Inner inner(tx, rx);
  ManualClock clock;
  sim::DelayedSendTransport<Inner, ManualClock> delayed(
      inner, clock, sim::DelaySettings{std::chrono::milliseconds(50), {}}, 0.0, 3);
  const std::array<std::byte, 3> datagram{std::byte{1}, std::byte{2}, std::byte{3}};
  REQUIRE(delayed.send(datagram) == endohaptics::transport::TransportStatus::ok);
  std::array<std::byte, 16> buffer{};
  std::size_t size = 0;
  bool truncated = false;
  clock.advance(std::chrono::milliseconds(49));
  (void)delayed.receive(buffer, std::chrono::nanoseconds(0));
  CHECK_FALSE(tx.pop(buffer, size, truncated));  // not yet due
  clock.advance(std::chrono::milliseconds(1));
  (void)delayed.receive(buffer, std::chrono::nanoseconds(0));
  REQUIRE(tx.pop(buffer, size, truncated));  // due: handed to the inner transport
  CHECK(size == 3);
  CHECK(buffer[2] == std::byte{3});

  sim::DelayedSendTransport<Inner, ManualClock> lossy(inner, clock, sim::DelaySettings{}, 0.1, 5);
  for (int i = 0; i < 10000; ++i) (void)lossy.send(datagram);
  CHECK(lossy.lost() > 850);
  CHECK(lossy.lost() < 1150);
  CHECK_THROWS_WITH((sim::DelayedSendTransport<Inner, ManualClock>(inner, clock, {}, 1.5, 1)),
                    doctest::Contains("loss must be in [0, 1], got 1.5"));
}

}  // namespace sim_passivity_sweep_test
