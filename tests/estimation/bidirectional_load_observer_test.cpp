#include "alloc_counter.hpp"  // first: counts every heap allocation of this executable

#include <doctest/doctest.h>

#include <cmath>
#include <endohaptics/estimation/bidirectional_load_observer.hpp>
#include <random>

#include "test_support.hpp"

namespace estimation_bidirectional_load_observer_test {

namespace est = endohaptics::estimation;
using endohaptics::model::NumericStatus;
using endohaptics::test::allocations_during;
using endohaptics::test::message_of;
using Observer = est::BidirectionalLoadObserver<double>;

namespace {

// A grasper at 1 kHz: +-0.5 rad at 0.2 Hz against a constant load. Moving forward the current is
// 1.4 mA per load unit + 70 mA, backward 0.7 mA per unit - 90 mA (the maps below), each shifted
// by this instrument's friction `friction` A (+ forward, - backward), which the model does not
// know; 2 mA noise.
constexpr double g_f = 1.4e-3, o_f = 0.07, g_b = 0.7e-3, o_b = -0.09;

Observer::Parameters parameters() {
  Observer::Parameters p;
  p.forward_gain = g_f;
  p.forward_offset = o_f;
  p.backward_gain = g_b;
  p.backward_offset = o_b;
  p.forward_variance = 100.0;   // (10 load units)^2 per sample: the inversions are correlated
  p.backward_variance = 400.0;  // (20)^2
  p.friction_variance = 100.0;  // (10)^2
  p.initial_load = 50.0;
  p.initial_variance = 900.0;
  return p;
}

// Runs `m` for `seconds` on the grasper with `load` and `friction` (A); returns the last output.
double drive(Observer& m, double load, double friction, double seconds, unsigned seed = 1) {
  std::mt19937 rng(seed);
  std::normal_distribution<double> noise(0.0, 0.002);
  const double w = 2 * 3.141592653589793 * 0.2;
  double y = 0.0;
  for (int k = 0; k < static_cast<int>(seconds * 1000); ++k) {
    const double t = 1e-3 * k;
    const double q = 0.5 * std::sin(w * t);
    const double v = 0.5 * w * std::cos(w * t);
    const double i =
        (v > 0 ? g_f * load + o_f + friction : g_b * load + o_b - friction) + noise(rng);
    const est::JointSignals<double> s{q, v, i, 0.0};
    REQUIRE(m.advance(s) == NumericStatus::ok);
    y = m.force(s);
  }
  return y;
}

}  // namespace

TEST_CASE("bidirectional observer: motion both ways cancels an unknown friction") {
  static_assert(est::JointForceModel<Observer>);
  // 10 mA of friction: 7.1 load units on the forward inversion, 14.3 on the backward one.
  Observer m(parameters());
  const double y = drive(m, 30.0, 0.01, 15.0);
  CHECK(y == doctest::Approx(30.0).epsilon(0.05));
  CHECK(m.friction_estimate() == doctest::Approx(0.01 / g_f).epsilon(0.1));
  // Without the friction state (its prior 0) the estimate is the two inversions' weighted mean:
  // biased by the friction.
  auto p = parameters();
  p.friction_variance = 0.0;
  Observer fixed(p);
  const double biased = drive(fixed, 30.0, 0.01, 15.0);
  MESSAGE("load 30, friction 10 mA: " << y << " with the friction state, " << biased << " without");
  CHECK(std::fabs(biased - 30.0) > 3.0 * std::fabs(y - 30.0));
  // No friction: the same estimate either way.
  Observer clean(parameters());
  CHECK(drive(clean, 30.0, 0.0, 15.0) == doctest::Approx(30.0).epsilon(0.03));
}

TEST_CASE("bidirectional observer: at rest nothing is learnt, the output's hysteresis follows") {
  auto p = parameters();
  p.output_offset = 1.0;
  p.output_shape[7] = 2.0;           // the widest operator
  p.output_shape_per_load[0] = 0.1;  // the narrowest, per load unit
  Observer m(p);
  const est::JointSignals<double> rest{0.2, 0.0, 0.03, 0.0};
  for (int k = 0; k < 100; ++k) REQUIRE(m.advance(rest) == NumericStatus::ok);
  CHECK(m.regime() == 0.0);
  CHECK(m.load_estimate() == 50.0);
  CHECK(m.stop_values().isZero(0.0));
  CHECK(m.force(rest) == doctest::Approx(51.0));
  // Moving forward by 0.3 rad: every operator started at -1 and moved up; the output adds
  // e0 + a_8 s_8 + b_1 L s_1 at the current load estimate.
  for (int k = 1; k <= 300; ++k) {
    REQUIRE(m.advance({0.2 + 0.001 * k, 1.0, 0.07 + g_f * 50.0, 0.0}) == NumericStatus::ok);
  }
  const auto s = m.stop_values();
  CHECK(s[0] == doctest::Approx(1.0));
  CHECK(s[7] == doctest::Approx(-1.0 + 0.3 / 0.5));
  CHECK(m.force(rest) ==
        doctest::Approx(m.load_estimate() + 1.0 + 2.0 * s[7] + 0.1 * m.load_estimate() * s[0]));
}

TEST_CASE("bidirectional observer: bad input leaves the state, no allocation per step") {
  Observer m(parameters());
  REQUIRE(m.advance({0.0, 0.0, 0.1, 0.0}) == NumericStatus::ok);
  const auto before = m.state();
  CHECK(m.advance({std::nan(""), 0.0, 0.1, 0.0}) == NumericStatus::non_finite_input);
  CHECK(m.advance({0.0, 0.0, INFINITY, 0.0}) == NumericStatus::non_finite_input);
  CHECK(m.state() == before);
  // A step whose result overflows is refused whole (non_finite_result), not half applied: load and
  // friction at 1e308 make the innovation -Inf on the first forward step.
  for (int k = 1; k <= 100; ++k) {  // moving forward at 1 rad/s: the regime is forward
    REQUIRE(m.advance({1e-3 * k, 1.0, 0.2, 0.0}) == NumericStatus::ok);
  }
  REQUIRE(m.regime() == 1.0);
  auto huge = m.state();
  huge[Observer::load] = 1e308;
  huge[Observer::friction] = 1e308;
  m.reset(huge);
  CHECK(m.advance({0.101, 1.0, 0.2, 0.0}) == NumericStatus::non_finite_result);
  CHECK(m.state() == huge);
  m.reset();
  CHECK(m.load_estimate() == 50.0);
  CHECK(m.state()[Observer::started] == 0.0);
  long steps = 0;
  const long allocations = allocations_during([&] {
    for (int k = 0; k < 10000; ++k) {
      const double q = 0.5 * std::sin(1e-3 * k);
      steps += m.advance({q, 0.0, 0.05 * std::cos(1e-3 * k), 0.0}) == NumericStatus::ok ? 1 : 0;
      (void)m.force({q, 0.0, 0.0, 0.0});
    }
  });
  CHECK(steps == 10000);
  CHECK(allocations == 0);
}

TEST_CASE("bidirectional observer: parameters out of range are refused, naming the field") {
  auto p = parameters();
  p.forward_gain_stroke = 1.3e-3;  // > 0.9 |g|: the map's gain would all but vanish
  CHECK(message_of([&] { Observer bad(p); }) ==
        "BidirectionalLoadObserverParameters: forward_gain_stroke must be at most 0.9 times the "
        "gain's magnitude (the gain keeps its sign and a tenth of its size along the stroke), "
        "got 0.0013");
  p = parameters();
  p.backward_gain = -0.7e-3;  // the current would fall with the load moving back
  CHECK(message_of([&] { Observer bad(p); }) ==
        "BidirectionalLoadObserverParameters: backward_gain must be of forward_gain's sign and at "
        "least 1e-6 times its magnitude (the current grows with the load both ways), got -7e-04");
  p = parameters();
  p.stop_thresholds[3] = p.stop_thresholds[2];
  CHECK(message_of([&] { Observer bad(p); }) ==
        "BidirectionalLoadObserverParameters: stop_thresholds[3] must be above the threshold "
        "before it, got 0.05");
  p = parameters();
  p.output_shape[2] = 1e300;
  CHECK(message_of([&] { Observer bad(p); }) ==
        "BidirectionalLoadObserverParameters: output_shape[2] must be in [-1e6, 1e6], got 1e+300");
  p = parameters();
  p.backward_variance = 0.0;
  CHECK(message_of([&] { Observer bad(p); }) ==
        "BidirectionalLoadObserverParameters: backward_variance must be in [1e-12, 1e6], got 0");
  p = parameters();
  p.friction_variance = std::nan("");
  CHECK(message_of([&] { Observer bad(p); }) ==
        "BidirectionalLoadObserverParameters: friction_variance must be in [0, 1e6], got nan");
  p = parameters();
  p.current_cutoff = 600.0;  // above Nyquist at 1 kHz
  CHECK(message_of([&] { Observer bad(p); }) ==
        "BidirectionalLoadObserverParameters: current_cutoff must be in (0, Nyquist = 0.5 / "
        "sample_time) Hz, got 600");
}

TEST_CASE("bidirectional observer: float") {
  est::BidirectionalLoadObserverParameters<float> p;
  p.forward_gain = 1.4e-3F;
  p.backward_gain = 0.7e-3F;
  p.initial_load = 10.0F;
  est::BidirectionalLoadObserver<float> m(p);
  CHECK(m.advance({0.0F, 0.0F, 0.1F, 0.0F}) == NumericStatus::ok);
  CHECK(m.force({0.0F, 0.0F, 0.1F, 0.0F}) == doctest::Approx(10.0F));
}

}  // namespace estimation_bidirectional_load_observer_test
