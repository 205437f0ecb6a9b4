#include "endohaptics/model/static_nonlinearity.hpp"

#include <doctest/doctest.h>

#include <array>
#include <cmath>
#include <limits>
#include <random>
#include <string>
#include <utility>
#include <vector>
#include "test_support.hpp"

namespace model_static_nonlinearity_test {

using endohaptics::test::message_of;

namespace {

using endohaptics::Error;
using endohaptics::model::Deadzone;
using endohaptics::model::Extrapolation;
using endohaptics::model::FreeMotionThreshold;
using endohaptics::model::Identity;
using endohaptics::model::PerChannel;
using endohaptics::model::PiecewiseLinear;
using endohaptics::model::Saturation;
using endohaptics::model::StaticNonlinearity;

bool contains(const std::string& text, const std::string& part) {
  return text.find(part) != std::string::npos;
}

// Contract of the StaticNonlinearity concept, reusable for any implementation (ours or a
// user's): NaN in gives NaN out, finite in gives finite out, apply is a pure function.
template <StaticNonlinearity NL>
void check_static_nonlinearity_contract(const NL& nl) {
  using S = typename NL::ScalarType;
  static_assert(noexcept(nl.apply(S(0))));
  CHECK(std::isnan(nl.apply(std::numeric_limits<S>::quiet_NaN())));
  std::mt19937_64 rng(99);
  std::uniform_real_distribution<double> dist(-10.0, 10.0);
  for (int i = 0; i < 1000; ++i) {
    const auto u = static_cast<S>(dist(rng));
    const S y = nl.apply(u);
    CHECK(std::isfinite(y));
    CHECK(nl.apply(u) == y);
  }
}

template <typename NL>
NL make_example();
template <>
Identity<double> make_example() {
  return {};
}
template <>
Deadzone<double> make_example() {
  return Deadzone<double>(-0.1, 0.3);
}
template <>
Deadzone<float> make_example() {
  return Deadzone<float>(0.2f);
}
template <>
Saturation<double> make_example() {
  return Saturation<double>(-1.0, 2.0);
}
template <>
FreeMotionThreshold<double> make_example() {
  return FreeMotionThreshold<double>(0.2);
}
template <>
PiecewiseLinear<4> make_example() {
  const std::array<double, 3> x{-1.0, 0.0, 2.0};
  const std::array<double, 3> y{1.0, 0.0, 4.0};
  return PiecewiseLinear<4>(x, y);
}

}  // namespace

static_assert(StaticNonlinearity<Identity<double>>);
static_assert(StaticNonlinearity<Deadzone<float>>);
static_assert(StaticNonlinearity<Saturation<double>>);
static_assert(StaticNonlinearity<PiecewiseLinear<8, float>>);
static_assert(!StaticNonlinearity<int>);

TEST_CASE_TEMPLATE("every nonlinearity satisfies the StaticNonlinearity contract", NL,
                   Identity<double>, Deadzone<double>, Deadzone<float>, Saturation<double>,
                   FreeMotionThreshold<double>, PiecewiseLinear<4>) {
  check_static_nonlinearity_contract(make_example<NL>());
}

// Expected values by hand from the MATLAB idDeadZone definition (ZeroInterval [a, b]):
// y = 0 for a <= u <= b, y = u - b for u > b, y = u - a for u < a.
TEST_CASE("Deadzone: symmetric (table 5.2 yaw, 0.21 A) and asymmetric, by hand") {
  const Deadzone<double> yaw(0.21);
  CHECK(yaw.lower() == -0.21);
  CHECK(yaw.upper() == 0.21);
  CHECK(yaw.apply(0.5) == doctest::Approx(0.29));
  CHECK(yaw.apply(-0.5) == doctest::Approx(-0.29));
  CHECK(yaw.apply(0.21) == 0.0);
  CHECK(yaw.apply(-0.21) == 0.0);
  CHECK(yaw.apply(0.1) == 0.0);
  CHECK(yaw.apply(0.0) == 0.0);
  CHECK(yaw.apply(std::numeric_limits<double>::infinity()) ==
        std::numeric_limits<double>::infinity());

  const Deadzone<double> asym(-0.1, 0.3);
  CHECK(asym.apply(1.0) == doctest::Approx(0.7));
  CHECK(asym.apply(-1.0) == doctest::Approx(-0.9));
  CHECK(asym.apply(0.3) == 0.0);
  CHECK(asym.apply(-0.1) == 0.0);
  CHECK(asym.apply(0.2) == 0.0);
  // A zero interval not containing 0 is allowed (shifts the map): [0.5, 1] maps 0 to -0.5.
  CHECK(Deadzone<double>(0.5, 1.0).apply(0.0) == doctest::Approx(-0.5));
  // Width 0 is the identity.
  CHECK(Deadzone<double>(0.0).apply(-0.37) == -0.37);
  CHECK(Deadzone<float>(0.2f).apply(1.0f) == doctest::Approx(0.8f));
}

TEST_CASE("Saturation: clamps to [lower, upper], by hand") {
  const Saturation<double> sat(-1.0, 2.0);
  CHECK(sat.apply(5.0) == 2.0);
  CHECK(sat.apply(-5.0) == -1.0);
  CHECK(sat.apply(1.5) == 1.5);
  CHECK(sat.apply(-std::numeric_limits<double>::infinity()) == -1.0);
  const Saturation<float> symmetric(0.5f);
  CHECK(symmetric.apply(-0.7f) == -0.5f);
  CHECK(symmetric.apply(0.25f) == 0.25f);
}

TEST_CASE("PiecewiseLinear: interpolation, linear and clamped extrapolation, by hand") {
  const std::array<double, 4> x{-1.0, 0.0, 1.0, 3.0};
  const std::array<double, 4> y{-2.0, 0.0, 1.0, 2.0};
  const PiecewiseLinear<6> linear(x, y);
  CHECK(linear.size() == 4);
  CHECK(linear.apply(-1.0) == -2.0);
  CHECK(linear.apply(0.0) == 0.0);
  CHECK(linear.apply(3.0) == 2.0);
  CHECK(linear.apply(0.5) == doctest::Approx(0.5));
  CHECK(linear.apply(-0.25) == doctest::Approx(-0.5));
  CHECK(linear.apply(2.0) == doctest::Approx(1.5));
  CHECK(linear.apply(-2.0) == doctest::Approx(-4.0));  // first slope 2 continued
  CHECK(linear.apply(5.0) == doctest::Approx(3.0));    // last slope 1/2 continued

  const PiecewiseLinear<4> clamped(x, y, Extrapolation::clamp);
  CHECK(clamped.apply(-2.0) == -2.0);
  CHECK(clamped.apply(5.0) == 2.0);
  CHECK(clamped.apply(2.0) == doctest::Approx(1.5));
  CHECK(clamped.apply(std::numeric_limits<double>::infinity()) == 2.0);
  // A flat end segment keeps +-Inf from producing NaN (0 * Inf).
  const std::array<double, 2> fx{0.0, 1.0};
  const std::array<double, 2> fy{3.0, 3.0};
  CHECK(PiecewiseLinear<2>(fx, fy).apply(std::numeric_limits<double>::infinity()) == 3.0);
}

TEST_CASE("PiecewiseLinear reproduces Deadzone (linear extrapolation) and Saturation (clamp)") {
  const std::array<double, 4> dx{-1.0, -0.2, 0.2, 1.0};
  const std::array<double, 4> dy{-0.8, 0.0, 0.0, 0.8};
  const PiecewiseLinear<4> pwl_deadzone(dx, dy);
  const Deadzone<double> deadzone(0.2);
  const std::array<double, 2> sx{-1.0, 1.0};
  const PiecewiseLinear<2> pwl_saturation(sx, sx, Extrapolation::clamp);
  const Saturation<double> saturation(1.0);
  for (double u = -3.0; u <= 3.0; u += 0.01) {
    CHECK(pwl_deadzone.apply(u) == doctest::Approx(deadzone.apply(u)).epsilon(1e-12));
    CHECK(pwl_saturation.apply(u) == doctest::Approx(saturation.apply(u)).epsilon(1e-12));
  }
}

TEST_CASE("invalid configuration throws Error naming the value") {
  CHECK(contains(message_of([] { Deadzone<double>(0.3, 0.1); }), "0.3"));
  CHECK(contains(message_of([] { Deadzone<double>(0.3, 0.1); }), "greater than"));
  CHECK(contains(message_of([] { Deadzone<double>(-0.21); }), "-0.21"));
  CHECK(contains(message_of([] { (void)Deadzone<double>(std::nan("")); }), "not finite"));
  CHECK(contains(message_of([] { Saturation<double>(1.0, -1.0); }), "Saturation"));
  CHECK_THROWS_AS((void)Saturation<float>(std::numeric_limits<float>::infinity()), Error);
  CHECK_NOTHROW((void)Saturation<double>(0.0));

  const std::array<double, 3> good{0.0, 1.0, 2.0};
  const std::array<double, 3> repeated{0.0, 1.0, 1.0};
  const std::array<double, 2> two{0.0, 1.0};
  const std::array<double, 1> one{0.0};
  const std::array<double, 3> with_nan{0.0, std::nan(""), 2.0};
  CHECK(contains(message_of([&] { PiecewiseLinear<4>(repeated, good); }), "x[2] = 1"));
  CHECK(contains(message_of([&] { PiecewiseLinear<4>(good, two); }), "3 breakpoints but 2"));
  CHECK(contains(message_of([&] { PiecewiseLinear<4>(one, one); }), "got 1"));
  CHECK(contains(message_of([&] { PiecewiseLinear<2>(good, good); }), "2 to 2 points, got 3"));
  CHECK(contains(message_of([&] { PiecewiseLinear<4>(good, with_nan); }), "point 1"));
}

TEST_CASE("PerChannel applies one nonlinearity per element (including N == 0)") {
  const PerChannel<Deadzone<double>, 3> channels(std::array<Deadzone<double>, 3>{
      Deadzone<double>(0.2), Deadzone<double>(0.0), Deadzone<double>(-1.0, 0.5)});
  const Eigen::Vector3d y = channels.apply(Eigen::Vector3d{0.5, -0.5, -2.0});
  CHECK(y[0] == doctest::Approx(0.3));
  CHECK(y[1] == -0.5);
  CHECK(y[2] == doctest::Approx(-1.0));
  CHECK(channels.channel(2).upper() == 0.5);

  const PerChannel<Saturation<float>, 2> same(Saturation<float>(1.0f));
  const Eigen::Vector2f ys = same.apply(Eigen::Vector2f{3.0f, -0.5f});
  CHECK(ys[0] == 1.0f);
  CHECK(ys[1] == -0.5f);

  const PerChannel<Identity<double>, 0> none;
  CHECK(none.apply(Eigen::Matrix<double, 0, 1>{}).size() == 0);
  const PerChannel<Identity<double>, 2> identity;
  CHECK(identity.apply(Eigen::Vector2d{1.5, -2.5}) == Eigen::Vector2d{1.5, -2.5});
  static_assert(noexcept(identity.apply(std::declval<const Eigen::Vector2d&>())));
}

TEST_CASE("FreeMotionThreshold: 0 up to t, the estimate beyond 2 t, continuous in between") {
  const FreeMotionThreshold<double> t(0.2);
  CHECK(t.threshold() == 0.2);
  CHECK(t.apply(0.0) == 0.0);
  CHECK(t.apply(0.2) == 0.0);
  CHECK(t.apply(-0.19) == 0.0);
  CHECK(t.apply(0.3) == doctest::Approx(0.2));    // 2 (0.3 - 0.2)
  CHECK(t.apply(-0.3) == doctest::Approx(-0.2));  // odd
  CHECK(t.apply(0.4) == 0.4);                     // continuous at 2 t
  CHECK(t.apply(0.39999) == doctest::Approx(0.39998));
  CHECK(t.apply(-5.0) == -5.0);
  // Monotonic: a larger estimate never renders less.
  double previous = -1e9;
  for (double u = -1.0; u <= 1.0; u += 1e-3) {
    CHECK(t.apply(u) >= previous - 1e-12);
    previous = t.apply(u);
  }
  // The default and a threshold of 0 are the identity; a negative or NaN threshold is refused.
  CHECK(FreeMotionThreshold<double>().apply(0.01) == 0.01);
  CHECK(FreeMotionThreshold<double>(0.0).apply(-0.01) == -0.01);
  CHECK_THROWS_AS(FreeMotionThreshold<double>(-0.1), Error);
  CHECK_THROWS_AS(FreeMotionThreshold<double>{std::numeric_limits<double>::quiet_NaN()}, Error);
}

}  // namespace model_static_nonlinearity_test
