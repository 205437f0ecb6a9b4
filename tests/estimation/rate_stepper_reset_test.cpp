#include "alloc_counter.hpp"  // first: counts every heap allocation of this executable

#include <doctest/doctest.h>

#include <endohaptics/estimation/push_load_observer.hpp>
#include <endohaptics/estimation/rate_policy.hpp>
#include <endohaptics/estimation/stall_hold.hpp>

namespace estimation_rate_stepper_reset_test {

namespace est = endohaptics::estimation;

// A reset (the estimator's, on a new link) must put a model where its own reset() puts it: the
// push-load observer starts from its initial load and variance. It used to be the zero state,
// which left the observer with variance 0 (a Kalman gain of 0 until the process noise grew it)
// and a load of 0 whatever the configured start.
TEST_CASE("rate stepper: reset returns each model to its own start state") {
  est::PushLoadObserverParameters<double> p;
  p.initial_load = 0.02;
  p.initial_variance = 3e-3;
  const est::PushLoadObserver<double> fresh(p);
  est::detail::force::RateStepper<est::PushLoadObserver<double>,
                                  est::detail::force::RateMode::decimate>
      stepper(fresh, p.sample_time, "clamp");
  double force = 0.0;
  for (int i = 0; i < 200; ++i) {
    const double t = 0.001 * i;
    REQUIRE(stepper.tick({0.3 * t, 0.3, 0.1 + 0.5 * t, 0.0}, force) ==
            endohaptics::model::NumericStatus::ok);
  }
  REQUIRE(stepper.snapshot().state != fresh.state());
  stepper.reset();
  CHECK(stepper.snapshot().state == fresh.state());
  CHECK(stepper.snapshot().state[7] == doctest::Approx(3e-3));  // the variance, not 0
  CHECK(stepper.snapshot().count == 0);

  // StallHold starts at the zero state.
  est::StallHoldParameters<double> h;
  h.sample_time = 0.01;
  est::detail::force::RateStepper<est::StallHold<double>, est::detail::force::RateMode::decimate>
      held(est::StallHold<double>(h), 0.001, "clamp");
  for (int i = 0; i < 50; ++i)
    REQUIRE(held.tick({0.0, 0.0, 0.5, 0.0}, force) == endohaptics::model::NumericStatus::ok);
  held.reset();
  CHECK(held.snapshot().state.isZero());
}

}  // namespace estimation_rate_stepper_reset_test
