#include "alloc_counter.hpp"  // first: counts every heap allocation of this executable

#include <doctest/doctest.h>

#include <cmath>
#include <endohaptics/estimation/current_offset_reference.hpp>
#include <limits>
#include <random>

#include "test_support.hpp"

namespace estimation_current_offset_reference_test {

namespace est = endohaptics::estimation;
using endohaptics::model::NumericStatus;
using endohaptics::test::allocations_during;
using endohaptics::test::message_of;

TEST_CASE("current offset reference: a session's measurement offset is moved to the reference") {
  // Trained where i = -2.06 u - 0.005 A; this session measures i = -2.06 u - 0.020 A (0.015 A
  // lower for the same command), with 5 mA noise and a command that sweeps.
  est::CurrentOffsetReferenceParameters<double> p;
  p.command_gain = -2.06;
  p.reference_offset = -0.005;
  est::CurrentOffsetReference<double> r(p);
  std::mt19937 rng(3);
  std::normal_distribution<double> noise(0.0, 0.005);
  double last_error = 0.0;
  bool all_ok = true;
  const auto allocations = allocations_during([&] {
    for (int k = 0; k < 5000; ++k) {
      const double u = 0.05 * std::sin(0.01 * k);
      const double true_current = -2.06 * u - 0.005;  // as the training sessions would read it
      const double measured = true_current - 0.015 + noise(rng);
      all_ok = all_ok && r.advance(measured, u) == NumericStatus::ok;
      last_error = r.corrected() - true_current;
    }
  });
  CHECK(allocations == 0);
  CHECK(all_ok);
  CHECK(r.offset() == doctest::Approx(-0.020).epsilon(0.02));
  // What is left is this sample's noise (the offset itself is gone).
  CHECK(std::fabs(last_error) < 0.02);
  CHECK(std::fabs(r.offset() - (-0.020)) < 0.0005);
}

TEST_CASE("current offset reference: non-finite input, bounds, reset") {
  est::CurrentOffsetReference<double> r({-2.0, 0.01});
  REQUIRE(r.advance(0.1, 0.02) == NumericStatus::ok);
  const auto before = r.state();
  const double corrected = r.corrected();
  CHECK(r.advance(std::nan(""), 0.0) == NumericStatus::non_finite_input);
  CHECK(r.advance(0.1, std::numeric_limits<double>::infinity()) == NumericStatus::non_finite_input);
  CHECK(r.state() == before);
  CHECK(r.corrected() == corrected);
  // The first sample: the running offset is that sample's, the corrected current the reference.
  CHECK(r.offset() == doctest::Approx(0.1 + 2.0 * 0.02));
  CHECK(corrected == doctest::Approx(0.1 - (0.14 - 0.01)));
  // Finite but overflowing: refused, state untouched.
  CHECK(r.advance(1e308, -1e308) == NumericStatus::non_finite_result);
  CHECK(r.state() == before);
  r.reset();
  CHECK(r.state().isZero());
  CHECK(message_of([] {
          est::CurrentOffsetReference<double> bad({0.0, 0.0});
        }) ==
        "CurrentOffsetReferenceParameters: command_gain must be of magnitude in [1e-9, 1e6], got "
        "0");
  CHECK(message_of([] {
          est::CurrentOffsetReference<double> bad({1.0, 1e300});
        }) ==
        "CurrentOffsetReferenceParameters: reference_offset must be in [-1e6, 1e6], got 1e+300");
}

}  // namespace estimation_current_offset_reference_test
