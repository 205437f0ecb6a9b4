#include "alloc_counter.hpp"  // first: counts every heap allocation of this executable

#include "endohaptics/model/hammerstein_wiener.hpp"

#include <doctest/doctest.h>

#include <cmath>
#include <limits>
#include <random>

#include "endohaptics/model/presets_2016.hpp"

namespace model_hammerstein_wiener_test {

namespace {

using endohaptics::model::Deadzone;
using endohaptics::model::HammersteinWiener;
using endohaptics::model::Identity;
using endohaptics::model::NumericStatus;
using endohaptics::model::PerChannel;
using endohaptics::model::Saturation;
using endohaptics::model::StateSpace;
using endohaptics::test::allocations_during;
namespace m = endohaptics::model;

template <typename M>
M random_matrix(std::mt19937_64& rng, double scale = 1.0) {
  std::uniform_real_distribution<double> dist(-scale, scale);
  M out;
  for (Eigen::Index i = 0; i < out.size(); ++i) {
    out.data()[i] = static_cast<typename M::Scalar>(dist(rng));
  }
  return out;
}

}  // namespace

TEST_CASE_TEMPLATE(
    "identity nonlinearities: HammersteinWiener behaves exactly like its linear block", SS,
    StateSpace<1, 1, 1>, StateSpace<2, 0, 1>, StateSpace<3, 2, 2>, StateSpace<6, 2, 1>,
    StateSpace<4, 3, 2, float>) {
  using Scalar = typename SS::ScalarType;
  std::mt19937_64 rng(11 + SS::states);
  SS linear(random_matrix<typename SS::MatrixA>(rng, 0.9 / SS::states),
            random_matrix<typename SS::MatrixB>(rng), random_matrix<typename SS::MatrixC>(rng),
            random_matrix<typename SS::MatrixD>(rng), Scalar(0.02));
  linear.reset(random_matrix<typename SS::State>(rng));
  HammersteinWiener<SS> hw(linear);
  static_assert(HammersteinWiener<SS>::inputs == SS::inputs);
  CHECK(hw.state() == linear.state());
  for (int k = 0; k < 100; ++k) {
    const auto u = random_matrix<typename SS::Input>(rng);
    CHECK(hw.output(u) == linear.output(u));
    CHECK(hw.step(u) == linear.step(u));
  }
  CHECK(hw.state() == linear.state());
  hw.reset();
  CHECK(hw.state().isZero());
  CHECK(hw.linear().state().isZero());
}

// Hand computation for x+ = 0.5 x + f(u), y = g(x + 0.5 f(u)), f = dead zone +-0.2,
// g = saturation [-0.3, 0.3]:
//   k=0: u=1.0  f=0.8   y=g(0 + 0.4)=0.3 (saturated)    x=0.8
//   k=1: u=0.1  f=0     y=g(0.8)=0.3                     x=0.4
//   k=2: u=-1.0 f=-0.8  y=g(0.4 - 0.4)=0                 x=-0.6
//   k=3: u=0.0  f=0     y=g(-0.6)=-0.3                   x=-0.3
//   k=4: u=0.25 f=0.05  y=g(-0.3 + 0.025)=-0.275         x=-0.1
TEST_CASE("dead zone in, saturation out: a first-order model stepped by hand") {
  using SS = StateSpace<1, 1, 1>;
  using HW =
      HammersteinWiener<SS, PerChannel<Deadzone<double>, 1>, PerChannel<Saturation<double>, 1>>;
  HW hw(SS(SS::MatrixA{{0.5}}, SS::MatrixB{{1.0}}, SS::MatrixC{{1.0}}, SS::MatrixD{{0.5}}, 0.02),
        PerChannel<Deadzone<double>, 1>(Deadzone<double>(0.2)),
        PerChannel<Saturation<double>, 1>(Saturation<double>(-0.3, 0.3)));
  const std::array<double, 5> u{1.0, 0.1, -1.0, 0.0, 0.25};
  const std::array<double, 5> y{0.3, 0.3, 0.0, -0.3, -0.275};
  const std::array<double, 5> x_after{0.8, 0.4, -0.6, -0.3, -0.1};
  for (std::size_t k = 0; k < u.size(); ++k) {
    INFO("k = " << k);
    CHECK(hw.step(SS::Input{u[k]})[0] == doctest::Approx(y[k]).epsilon(1e-14));
    CHECK(hw.state()[0] == doctest::Approx(x_after[k]).epsilon(1e-14));
  }
  CHECK(hw.output_nonlinearity().channel(0).upper() == 0.3);
}

TEST_CASE("NaN input: update refuses it untouched, step propagates it without UB, reset recovers") {
  auto hw = m::yaw_force_2016_hw();
  const Eigen::Vector2d good{0.5, 0.1};
  const Eigen::Vector2d nan_current{std::numeric_limits<double>::quiet_NaN(), 0.1};
  Eigen::Matrix<double, 1, 1> y{42.0};
  REQUIRE(hw.update(good, y) == NumericStatus::ok);
  const auto state = hw.state();
  const double y_good = y[0];
  CHECK(y_good != 42.0);

  Eigen::Matrix<double, 1, 1> untouched{42.0};
  CHECK(hw.update(nan_current, untouched) == NumericStatus::non_finite_input);
  CHECK(untouched[0] == 42.0);
  CHECK(hw.state() == state);
  CHECK(hw.update(Eigen::Vector2d{0.1, std::numeric_limits<double>::infinity()}, untouched) ==
        NumericStatus::non_finite_input);

  // step does not check: the dead zone passes NaN on, the state becomes NaN.
  CHECK(std::isfinite(hw.step(good)[0]));
  (void)hw.step(nan_current);
  CHECK_FALSE(hw.state().allFinite());
  CHECK(std::isnan(hw.step(good)[0]));
  hw.reset();
  CHECK(hw.state().isZero());
  CHECK(std::isfinite(hw.step(good)[0]));
}

TEST_CASE("no heap allocation in 10,000 ticks (operator new counter and EIGEN_RUNTIME_NO_MALLOC)") {
  auto hw = m::yaw_force_2016_hw();
  auto linear = m::pitch_force_2016();
  auto roll = m::roll_torque_2016();
  auto combined = m::parallel(m::yaw_force_2016(), m::pitch_force_2016());
  double sink = 0.0;
  const long allocations = allocations_during([&] {
    Eigen::Matrix<double, 1, 1> y;
    for (int k = 0; k < 10000; ++k) {
      const Eigen::Vector2d u{0.4 * std::sin(0.01 * k), 0.2 * std::cos(0.01 * k)};
      sink += hw.step(u)[0];
      sink += linear.step(u)[0] * 1e-6;
      sink += roll.step(u.head<1>())[0];
      if (hw.update(u, y) == NumericStatus::ok) sink += y[0];
      sink += combined.step(Eigen::Vector4d{u[0], u[1], u[0], u[1]})[1] * 1e-6;
    }
  });
  CHECK(std::isfinite(sink));
  CHECK(allocations == 0);

  // The detector works: the 2016 way (dynamic sizes) allocates on every step.
  const Eigen::MatrixXd A = m::yaw_force_2016().A();
  const Eigen::MatrixXd B = m::yaw_force_2016().B();
  Eigen::VectorXd x = Eigen::VectorXd::Zero(6);
  const long dynamic_allocations = allocations_during([&] {
    for (int k = 0; k < 10; ++k) {
      Eigen::VectorXd u(2);
      u << 0.3, 0.1;
      x = A * x + B * u;
    }
  });
  CHECK(dynamic_allocations >= 10);
}

}  // namespace model_hammerstein_wiener_test
