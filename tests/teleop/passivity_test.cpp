// TimeDomainPassivity on synthetic ports: a 1-DOF spring environment behind a delay, driven
// by a sinusoidal operator motion, so every energy can be computed by hand.
#include "alloc_counter.hpp"  // first: counts every heap allocation of this executable

#include <doctest/doctest.h>

#include <cmath>
#include <cstdio>
#include <deque>
#include <endohaptics/teleop/passivity.hpp>
#include <endohaptics/teleop/tick_recorder.hpp>
#include <limits>
#include <numbers>
#include <string>

namespace teleop_passivity_test {

namespace {

namespace tp = endohaptics::teleop;
using Vector = tp::TimeDomainPassivity::Vector;
using endohaptics::test::allocations_during;

constexpr int clamp1 = 2;

// Clamp 1 presses a spring of stiffness k (N/rad) beyond q = 0 while the operator's desired
// setpoint follows a sine; the setpoint is sent as desired; the force comes back `delay` ticks
// late (0: the force of this tick's setpoint). Returns the lowest observer value.
struct SpringRun {
  double min_energy = 0.0;
  double min_energy_to_operator = 0.0;  // the operator-side observer (per-direction form)
  double min_gain = 1.0;                // the operator-side force scale
  double max_rendered = 0.0;
  double max_estimate = 0.0;
  bool reversed_force = false;
  bool reversed_step = false;
};

// The run with `config` (its round_trip_ticks the force's delay).
SpringRun run_spring(const tp::PassivityConfig& config, int ticks = 4000) {
  const int delay = config.round_trip_ticks;
  tp::TimeDomainPassivity tdpa(config);
  const double dt = 1e-3, k = 5.0;
  std::deque<double> forces(static_cast<std::size_t>(delay) + 1, 0.0);  // in flight
  Vector sent = Vector::Zero();
  tdpa.reset(sent);
  Vector force = Vector::Zero();
  SpringRun r;
  for (int t = 0; t < ticks; ++t) {
    Vector desired = Vector::Zero();
    desired[clamp1] = 0.05 + 0.05 * std::sin(2 * std::numbers::pi * 2.0 * t * dt);
    tdpa.track_desired(desired);
    Vector out;
    (void)tdpa.shape_setpoint(desired, force, out);
    if ((out[clamp1] - sent[clamp1]) * (desired[clamp1] - sent[clamp1]) < 0.0) {
      r.reversed_step = true;
    }
    sent = out;
    tdpa.commit(sent);
    // The robot follows the setpoint exactly; the force leaves now and arrives `delay` later.
    forces.push_back(-k * std::max(sent[clamp1], 0.0));
    forces.pop_front();
    force = Vector::Zero();
    force[clamp1] = forces.front();
    Vector robot = Vector::Zero();
    robot[clamp1] = sent[clamp1];  // (delay ignored for the reported motion: it only adds)
    tdpa.observe_robot(robot, force);
    Vector rendered;
    (void)tdpa.shape_force(force, dt, rendered);
    if (rendered[clamp1] * force[clamp1] < 0.0) r.reversed_force = true;
    r.max_rendered = std::max(r.max_rendered, std::fabs(rendered[clamp1]));
    r.max_estimate = std::max(r.max_estimate, std::fabs(force[clamp1]));
    r.min_energy = std::min(r.min_energy, tdpa.energy(clamp1));
    r.min_energy_to_operator = std::min(r.min_energy_to_operator, tdpa.energy_to_operator(clamp1));
    r.min_gain = std::min(r.min_gain, tdpa.figures().force_gain);
  }
  return r;
}

SpringRun run_spring(tp::PassivityMode mode, int delay, int ticks = 4000) {
  tp::PassivityConfig config;
  config.mode = mode;
  config.round_trip_ticks = delay;
  return run_spring(config, ticks);
}

}  // namespace

TEST_CASE("passivity: PassivityConfig::validate names the field and the value") {
  tp::PassivityConfig c;
  CHECK_NOTHROW(c.validate());
  c.round_trip_ticks = -1;
  CHECK_THROWS_WITH(c.validate(),
                    doctest::Contains("round_trip_ticks must be in [0, 1023], got -1"));
  c = {};
  c.lever[1] = 0.0;
  CHECK_THROWS_WITH(c.validate(), doctest::Contains("lever[1] must be finite and > 0"));
  c = {};
  c.energy_reserve = -1.0;
  CHECK_THROWS_WITH(c.validate(), doctest::Contains("energy_reserve"));
  c = {};
  c.force_limit[3] = std::nan("");
  CHECK_THROWS_WITH(c.validate(), doctest::Contains("force_limit[3]"));
  c = {};
  c.mode = static_cast<tp::PassivityMode>(7);
  CHECK_THROWS_WITH(c.validate(), doctest::Contains("mode must be off, observe or tdpa, got 7"));
  c = {};
  c.estimate_tolerance[2] = -0.1;
  CHECK_THROWS_WITH(c.validate(),
                    doctest::Contains("estimate_tolerance[2] must be in [0, 10] N, got -0.1"));
  c = {};
  c.observer = static_cast<tp::PassivityObserver>(5);
  CHECK_THROWS_WITH(
      c.validate(),
      doctest::Contains(R"(observer must be one of "combined" or "per_direction", got 5)"));
  c = {};
  c.gain_recovery_rate = std::numeric_limits<double>::infinity();
  CHECK_THROWS_WITH(c.validate(), doctest::Contains("gain_recovery_rate must be finite and > 0 "
                                                    "1/s, got inf"));
  c = {};
  c.lever[1] = 0.0;
  CHECK_THROWS_WITH(c.validate(),
                    doctest::Contains("lever[1] must be finite and > 0 m/rad, got 0"));
  CHECK(tp::to_string(tp::PassivityMode::tdpa) == "tdpa");
  CHECK(tp::to_string(tp::PassivityMode::observe) == "observe");
}

TEST_CASE("passivity: without delay the observer of a spring channel stays at zero") {
  const SpringRun r = run_spring(tp::PassivityMode::observe, 0);
  CHECK(r.max_estimate > 0.2);  // the spring was pressed
  CHECK(r.min_energy > -1e-9);
}

TEST_CASE("passivity: a delayed spring generates energy, and the observer shows it") {
  const SpringRun r = run_spring(tp::PassivityMode::observe, 100);
  CHECK(r.min_energy < -1e-3);  // J: ~2 Hz motion against a 100 ms late spring
  CHECK(r.max_rendered == doctest::Approx(r.max_estimate));  // observe changes nothing
}

TEST_CASE("passivity: with TDPA the controllers bound the deficit and only ever take away") {
  const SpringRun off = run_spring(tp::PassivityMode::observe, 100);
  const SpringRun on = run_spring(tp::PassivityMode::tdpa, 100);
  tp::PassivityConfig defaults;
  CHECK(on.min_energy > -defaults.energy_reserve - 1e-3);
  CHECK(on.min_energy > off.min_energy);
  CHECK_FALSE(on.reversed_force);  // the operator-side PC scales the force down, never flips it
  CHECK_FALSE(on.reversed_step);   // the robot-side PC shortens steps, never reverses them
  CHECK(on.max_rendered <= on.max_estimate + 1e-12);
}

TEST_CASE("passivity: off passes everything through and reports zeros") {
  tp::TimeDomainPassivity off;
  CHECK_FALSE(off.enabled());
  off.reset(Vector::Zero());
  Vector f = Vector::Constant(1.5), out;
  off.track_desired(Vector::Constant(0.1));
  CHECK_FALSE(off.shape_setpoint(Vector::Constant(0.2), f, out));
  CHECK(out == Vector::Constant(0.2));
  CHECK_FALSE(off.shape_force(f, 1e-3, out));
  CHECK(out == f);
  const tp::PassivityFigures fig = off.figures();
  CHECK(fig.energy == 0.0);
  CHECK(fig.force_gain == 1.0);
}

TEST_CASE("passivity: a tick of the controllers allocates nothing") {
  tp::PassivityConfig config;
  config.mode = tp::PassivityMode::tdpa;
  config.round_trip_ticks = 50;
  SUBCASE("combined") {}
  SUBCASE("per direction, tolerant, recovering while absorbing") {
    config.observer = tp::PassivityObserver::per_direction;
    config.estimate_tolerance = Vector::Constant(0.05);
    config.recover_while_absorbing = true;
    config.robot_return_needs_motion = false;
  }
  tp::TimeDomainPassivity tdpa(config);
  tdpa.reset(Vector::Zero());
  Vector out, force = Vector::Constant(-0.5);
  const long n = allocations_during([&] {
    for (int t = 0; t < 10000; ++t) {
      tdpa.track_desired(Vector::Constant(1e-4 * (t % 100)));
      (void)tdpa.shape_setpoint(Vector::Constant(1e-4 * (t % 100)), force, out);
      tdpa.commit(out);
      tdpa.observe_robot(out, force);
      (void)tdpa.shape_force(force, 1e-3, out);
    }
  });
  CHECK(n == 0);
}

// The hand presses clamp 1 into a constant force (it does work on the channel, gets none) while
// the setpoint sent runs twice as far as the hand's (the robot port puts out twice what the
// operator put in): operator -> robot is in deficit, robot -> operator is not. Returns the
// smallest force scale, and the figures at the end.
struct PressRun {
  double min_gain = 1.0;
  tp::PassivityFigures end{};
};

PressRun run_press_against(tp::PassivityObserver observer) {
  tp::PassivityConfig config;
  config.mode = tp::PassivityMode::tdpa;
  config.observer = observer;
  tp::TimeDomainPassivity tdpa(config);
  tdpa.reset(Vector::Zero());
  Vector force = Vector::Zero();
  force[clamp1] = -0.5;  // N, pushing the clamp back (against the press)
  PressRun r;
  for (int t = 1; t <= 2000; ++t) {
    Vector desired = Vector::Zero(), sent = Vector::Zero();
    desired[clamp1] = 1e-4 * t;
    sent[clamp1] = 2e-4 * t;
    tdpa.track_desired(desired);
    tdpa.commit(sent);  // (no robot-side shaping: the deficit is the point)
    tdpa.observe_robot(sent, force);
    Vector out;
    (void)tdpa.shape_force(force, 1e-3, out);
    r.min_gain = std::min(r.min_gain, tdpa.figures().force_gain);
  }
  r.end = tdpa.figures();
  return r;
}

TEST_CASE(
    "passivity: per-direction observers: a deficit towards the robot leaves the force alone") {
  const PressRun combined = run_press_against(tp::PassivityObserver::combined);
  const PressRun split = run_press_against(tp::PassivityObserver::per_direction);
  // 2000 ticks x 1e-4 rad x 0.32 m/rad x 0.5 N: the operator put in ~0.032 J, the setpoint
  // put ~0.064 J into the environment.
  CHECK(split.end.energy_to_robot < -0.02);
  CHECK(split.end.energy_to_operator == doctest::Approx(0.0).epsilon(1e-12));
  CHECK(split.min_gain == 1.0);     // the hand got no energy: nothing to take away from it
  CHECK(combined.min_gain == 0.0);  // one observer: the robot side's deficit scales the force
}

TEST_CASE("passivity: per-direction: the operator side's scaling does not feed its observer") {
  // A spring 100 ms late: the operator-side PC scales the force down; in the per-direction
  // form the robot side books the operator's input with the force before that scaling, so the
  // robot-side deficit is no larger than with the PC's scaling left out of the books.
  tp::PassivityConfig config;
  config.mode = tp::PassivityMode::tdpa;
  config.round_trip_ticks = 100;
  config.observer = tp::PassivityObserver::per_direction;
  const SpringRun r = run_spring(config);
  CHECK_FALSE(r.reversed_force);  // scaled, never reversed
  CHECK(r.min_gain < 1.0);        // the operator-side PC acted
  // ... and held its own direction within the reserve (plus a tick's energy)
  CHECK(r.min_energy_to_operator > -config.energy_reserve - 1e-3);
}

TEST_CASE("passivity: a force within the estimate tolerance is neither booked nor rendered") {
  tp::PassivityConfig config;
  config.mode = tp::PassivityMode::tdpa;
  config.estimate_tolerance[clamp1] = 0.1;
  tp::TimeDomainPassivity tdpa(config);
  tdpa.reset(Vector::Zero());
  Vector force = Vector::Zero(), out;
  force[clamp1] = 0.08;  // an estimate error in free motion, pushing the hand along
  for (int t = 1; t <= 1000; ++t) {
    Vector desired = Vector::Zero();
    desired[clamp1] = 1e-4 * t;
    tdpa.track_desired(desired);
    (void)tdpa.shape_setpoint(desired, force, out);
    tdpa.commit(out);
    tdpa.observe_robot(out, force);
    (void)tdpa.shape_force(force, 1e-3, out);
    CHECK(out[clamp1] == 0.0);
  }
  CHECK(tdpa.figures().energy == 0.0);
  CHECK(tdpa.figures().force_gain == 1.0);
  force[clamp1] = -0.3;  // a contact: felt less the tolerance
  (void)tdpa.shape_force(force, 1e-3, out);
  CHECK(out[clamp1] == doctest::Approx(-0.2));
}

TEST_CASE("passivity: a step against a force within the robot cost tolerance is not held back") {
  for (const double tolerance : {0.0, 0.05}) {
    CAPTURE(tolerance);
    tp::PassivityConfig config;
    config.mode = tp::PassivityMode::tdpa;
    config.observer = tp::PassivityObserver::per_direction;
    config.robot_cost_tolerance[clamp1] = tolerance;
    tp::TimeDomainPassivity tdpa(config);
    tdpa.reset(Vector::Zero());
    Vector force = Vector::Zero(), out, sent = Vector::Zero();
    force[clamp1] = -0.5;              // a contact pushing back against the setpoint's motion
    for (int t = 1; t <= 2000; ++t) {  // the setpoint goes twice as far as the hand: a deficit
      Vector desired = Vector::Zero();
      desired[clamp1] = 1e-4 * t;
      sent[clamp1] = 2e-4 * t;
      tdpa.track_desired(desired);
      tdpa.commit(sent);
      tdpa.observe_robot(sent, force);
      (void)tdpa.shape_force(force, 1e-3, out);
    }
    REQUIRE(tdpa.energy_to_robot(clamp1) < -0.02);  // J, standing: nothing will repay it
    Vector candidate = sent;
    candidate[clamp1] += 4e-3;  // one rate-limited step further in
    force[clamp1] = -0.02;      // what is left of the force: within the tolerance
    (void)tdpa.shape_setpoint(candidate, sent, force, out);
    CHECK(out[clamp1] == (tolerance > 0.0 ? candidate[clamp1] : sent[clamp1]));
    force[clamp1] = -0.3;  // a contact beyond it is still charged: the step is held back
    (void)tdpa.shape_setpoint(candidate, sent, force, out);
    CHECK(out[clamp1] == sent[clamp1]);
    CHECK(tdpa.energy_to_robot(clamp1) < -0.02);  // the observer books what it booked
  }
  tp::PassivityConfig bad;
  bad.robot_cost_tolerance[3] = -1.0;
  CHECK_THROWS_WITH(bad.validate(),
                    doctest::Contains("robot_cost_tolerance[3] must be in [0, 10] N, got -1"));
  bad.robot_cost_tolerance[3] = 11.0;  // beyond the estimator's output limit: a typo
  CHECK_THROWS_WITH(bad.validate(),
                    doctest::Contains("robot_cost_tolerance[3] must be in [0, 10] N, got 11"));
}

TEST_CASE("passivity: recover_while_absorbing brings the force back while the hand holds still") {
  for (const bool recover : {false, true}) {
    CAPTURE(recover);
    tp::PassivityConfig config;
    config.mode = tp::PassivityMode::tdpa;
    config.recover_while_absorbing = recover;
    tp::TimeDomainPassivity tdpa(config);
    tdpa.reset(Vector::Zero());
    Vector force = Vector::Zero(), out;
    force[clamp1] = 0.5;  // pushes the hand along its motion: the hand gets energy
    Vector desired = Vector::Zero();
    for (int t = 1; t <= 600; ++t) {  // 0.5 N x 0.32 m/rad x 0.06 rad: the reserve is spent
      desired[clamp1] = 1e-4 * t;
      tdpa.track_desired(desired);
      tdpa.commit(desired);
      tdpa.observe_robot(Vector::Zero(), force);  // the robot reports no motion: nothing back
      (void)tdpa.shape_force(force, 1e-3, out);
    }
    const double after_push = tdpa.figures().force_gain;
    CHECK(after_push < 0.6);
    for (int t = 0; t < 2000; ++t) {  // 2 s of a still hand
      tdpa.track_desired(desired);
      tdpa.commit(desired);
      tdpa.observe_robot(Vector::Zero(), force);
      (void)tdpa.shape_force(force, 1e-3, out);
    }
    if (recover) {
      CHECK(tdpa.figures().force_gain ==
            doctest::Approx(std::min(1.0, after_push + 2.0 * config.gain_recovery_rate)));
    } else {
      CHECK(tdpa.figures().force_gain == doctest::Approx(after_push));
    }
  }
}

TEST_CASE("passivity: the energy figures reach the tick log, by column name") {
  tp::TickResult r;
  r.passivity.energy = -0.0042;
  r.passivity.damping = 12.5;
  r.passivity.force_gain = 0.75;
  r.passivity.drift = 0.002;
  r.stylus_force = Eigen::Vector3d(0.5, -1.25, 0.0);
  tp::TickRecorder recorder(4);
  REQUIRE(recorder.push(tp::TickRecord::from(r, std::chrono::milliseconds(3))));
  std::FILE* out = std::tmpfile();
  REQUIRE(out != nullptr);
  tp::TickRecorder::write_header(out);
  CHECK(recorder.drain(out) == 1);
  std::rewind(out);
  char buf[2048] = {};
  const std::size_t n = std::fread(buf, 1, sizeof buf - 1, out);
  std::fclose(out);
  const std::string text(buf, n);
  const std::string header = text.substr(0, text.find('\n'));
  const std::string row = text.substr(text.find('\n') + 1);
  CHECK(header.find(",passivity_energy,passivity_damping,passivity_force_gain,passivity_drift,") !=
        std::string::npos);
  CHECK(row.find(",-0.0042,12.5,0.75,0.002,0.5,-1.25,0") != std::string::npos);
}

}  // namespace teleop_passivity_test
