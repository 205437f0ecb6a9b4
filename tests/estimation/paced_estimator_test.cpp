#include "alloc_counter.hpp"  // first: counts every heap allocation of this executable

#include <doctest/doctest.h>

#include <chrono>
#include <endohaptics/estimation/paced_estimator.hpp>

namespace estimation_paced_estimator_test {

namespace {

namespace est = endohaptics::estimation;
namespace tp = endohaptics::estimation;
using namespace std::chrono_literals;

// Counts its steps; the force is the step count (so a test sees which step it came from).
struct CountingEstimator {
  int steps = 0;
  int resets = 0;
  bool refuse = false;
  bool estimate(const tp::MotorState4& measured, const tp::MotorVector&,
                tp::MotorVector& force) noexcept {
    ++steps;
    if (refuse) return false;
    force.setConstant(steps);
    force[3] = measured.position[3];
    return true;
  }
  void reset() noexcept { ++resets; }
};

}  // namespace

TEST_CASE("faster ticks than the period hold the force, one step per elapsed period") {
  CountingEstimator inner;
  endohaptics::ManualClock clock(10s);
  est::PacedEstimator paced(inner, clock, 1ms);
  tp::MotorState4 state;
  tp::MotorVector force;
  for (int i = 0; i < 100; ++i) {  // 100 ticks at 20 kHz = 5 ms
    CHECK(paced.estimate(state, tp::MotorVector::Zero(), force));
    clock.advance(50us);
  }
  CHECK(inner.steps == 5);  // at 0, 1, 2, 3, 4 ms
  CHECK(force[0] == 5.0);
  CHECK(paced.counters().steps == 5);
  CHECK(paced.counters().held == 95);
}

TEST_CASE("a late call catches up the missed periods with the newest signals, bounded") {
  CountingEstimator inner;
  endohaptics::ManualClock clock(1s);
  est::PacedEstimator paced(inner, clock, 1ms, 20);
  tp::MotorState4 state;
  tp::MotorVector force;
  REQUIRE(paced.estimate(state, tp::MotorVector::Zero(), force));  // t = 0: step 1
  clock.advance(5ms);                                              // 5 periods due
  state.position[3] = 0.25;
  REQUIRE(paced.estimate(state, tp::MotorVector::Zero(), force));
  CHECK(inner.steps == 6);
  CHECK(force[3] == 0.25);
  clock.advance(100ms);  // 100 periods due, 20 run, 80 dropped and counted
  REQUIRE(paced.estimate(state, tp::MotorVector::Zero(), force));
  CHECK(inner.steps == 26);
  CHECK(paced.counters().skipped == 80);
  clock.advance(1ms);  // back on the grid: one step
  REQUIRE(paced.estimate(state, tp::MotorVector::Zero(), force));
  CHECK(inner.steps == 27);
}

TEST_CASE("a refused step is reported, and reset restarts the grid and the wrapped estimator") {
  CountingEstimator inner;
  endohaptics::ManualClock clock(1s);
  est::PacedEstimator paced(inner, clock, 1ms);
  tp::MotorState4 state;
  tp::MotorVector force;
  REQUIRE(paced.estimate(state, tp::MotorVector::Zero(), force));
  inner.refuse = true;
  clock.advance(1ms);
  CHECK(!paced.estimate(state, tp::MotorVector::Zero(), force));
  CHECK(paced.counters().rejected == 1);
  CHECK(!paced.estimate(state, tp::MotorVector::Zero(), force));  // held: still no valid force
  paced.reset();
  CHECK(inner.resets == 1);
  inner.refuse = false;
  clock.advance(300us);
  CHECK(paced.estimate(state, tp::MotorVector::Zero(), force));  // steps at once after a reset
  CHECK(inner.steps == 3);
}

TEST_CASE("pacing allocates nothing") {
  CountingEstimator inner;
  endohaptics::ManualClock clock(1s);
  est::PacedEstimator paced(inner, clock, 1ms);
  tp::MotorState4 state;
  tp::MotorVector force;
  const long n = endohaptics::test::allocations_during([&] {
    for (int i = 0; i < 10000; ++i) {
      clock.advance(170us);
      (void)paced.estimate(state, tp::MotorVector::Zero(), force);
    }
  });
  CHECK(n == 0);
  CHECK(inner.steps == 1700);
}

}  // namespace estimation_paced_estimator_test
