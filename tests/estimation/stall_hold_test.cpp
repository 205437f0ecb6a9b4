#include "alloc_counter.hpp"  // first: counts every heap allocation of this executable

#include <doctest/doctest.h>

#include <cmath>
#include <endohaptics/estimation/stall_hold.hpp>
#include <limits>

#include "test_support.hpp"

namespace estimation_stall_hold_test {

namespace est = endohaptics::estimation;
using endohaptics::test::allocations_during;
using endohaptics::test::message_of;

namespace {

est::StallHoldParameters<double> params(est::StallHoldSide side = est::StallHoldSide::negative) {
  est::StallHoldParameters<double> p;
  p.current_deadzone = 0.2;
  p.velocity_threshold = 0.05;
  p.velocity_time_constant = 0.0;  // no velocity filter: the test controls the regime directly
  p.output_time_constant = 0.0;    // no lag: the output is gain x the held value
  p.gain = 8.0;                    // N/A
  p.side = side;
  p.sample_time = 0.01;
  return p;
}

est::JointSignals<double> signals(double current, double velocity) {
  return {0.0, velocity, current, 0.0};
}

}  // namespace

TEST_CASE("stall-hold: follows the current while moving, holds it while stalled") {
  est::StallHold<double> m(params());
  static_assert(est::JointForceModel<est::StallHold<double>>);
  // Moving into the object: current -0.97 A -> held -(0.97 - 0.2), force 8 x that.
  REQUIRE(m.advance(signals(-0.97, 0.07)) == endohaptics::model::NumericStatus::ok);
  CHECK(m.force(signals(-0.97, 0.07)) == doctest::Approx(8.0 * -0.77));
  // Stalled: the current relaxes to -0.05 A, the force stays (tendon stiction holds it).
  REQUIRE(m.advance(signals(-0.05, 0.0)) == endohaptics::model::NumericStatus::ok);
  CHECK(m.force(signals(-0.05, 0.0)) == doctest::Approx(8.0 * -0.77));
  // Moving back out: the current is inside the dead zone, the force goes.
  REQUIRE(m.advance(signals(0.1, -0.07)) == endohaptics::model::NumericStatus::ok);
  CHECK(m.force(signals(0.1, -0.07)) == 0.0);
  // negative side: positive current beyond the dead zone gives no force.
  REQUIRE(m.advance(signals(0.9, -0.07)) == endohaptics::model::NumericStatus::ok);
  CHECK(m.force(signals(0.9, -0.07)) == 0.0);
}

TEST_CASE("stall-hold: sides, lags, the state, non-finite input") {
  CHECK(est::StallHold<double>(params(est::StallHoldSide::both)).beyond_deadzone(0.5) ==
        doctest::Approx(0.3));
  CHECK(est::StallHold<double>(params(est::StallHoldSide::both)).beyond_deadzone(-0.5) ==
        doctest::Approx(-0.3));
  CHECK(est::StallHold<double>(params(est::StallHoldSide::positive)).beyond_deadzone(-0.5) == 0.0);
  CHECK(est::StallHold<double>(params(est::StallHoldSide::negative)).beyond_deadzone(0.5) == 0.0);

  // A 0.3 s output lag at 10 ms: after one step, alpha = 0.01 / 0.31 of the held value.
  auto p = params();
  p.output_time_constant = 0.3;
  est::StallHold<double> m(p);
  REQUIRE(m.advance(signals(-1.2, 0.1)) == endohaptics::model::NumericStatus::ok);
  CHECK(m.state()[1] == doctest::Approx(-1.0));
  CHECK(m.state()[2] == doctest::Approx(-1.0 * 0.01 / 0.31));
  const auto before = m.state();
  CHECK(m.advance(signals(std::numeric_limits<double>::quiet_NaN(), 0.1)) ==
        endohaptics::model::NumericStatus::non_finite_input);
  CHECK(m.state() == before);  // untouched
  m.reset();
  CHECK(m.state().isZero());
}

TEST_CASE("stall-hold: parameters are checked, steps allocate nothing") {
  auto p = params();
  p.current_deadzone = -0.1;
  CHECK(message_of([&] { est::StallHold<double> bad(p); }) ==
        "StallHoldParameters: current_deadzone must be in [0, 1e6] A, got -0.1");
  p = params();
  p.gain = 1e300;  // finite, but gain x current would overflow the estimate
  CHECK(message_of([&] { est::StallHold<double> bad(p); }) ==
        "StallHoldParameters: gain must be in [-1e6, 1e6], got 1e+300");
  p = params();
  p.sample_time = 0.0;
  CHECK(message_of([&] { est::StallHold<double> bad(p); }) ==
        "StallHoldParameters: sample_time must be finite and > 0 s, got 0");
  est::StallHold<double> m(params());
  double sink = 0.0;
  const long allocations = allocations_during([&] {
    for (int k = 0; k < 10000; ++k) {
      const auto s = signals(std::sin(0.01 * k), std::cos(0.013 * k));
      (void)m.advance(s);
      sink += m.force(s);
    }
  });
  CHECK(allocations == 0);
  CHECK(std::isfinite(sink));
}

}  // namespace estimation_stall_hold_test
