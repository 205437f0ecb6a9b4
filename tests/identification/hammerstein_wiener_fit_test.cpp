#include "endohaptics/identification/hammerstein_wiener_fit.hpp"

#include <doctest/doctest.h>

#include <cmath>
#include <random>
#include <vector>

namespace identification_hammerstein_wiener_fit_test {

namespace {

namespace id = endohaptics::identification;
using Eigen::MatrixXd;
using Eigen::VectorXd;
using endohaptics::Error;

MatrixXd uniform(Eigen::Index rows, Eigen::Index cols, double half_range, unsigned seed) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> dist(-half_range, half_range);
  MatrixXd m(rows, cols);
  for (Eigen::Index i = 0; i < m.size(); ++i) m.data()[i] = dist(rng);
  return m;
}

MatrixXd gaussian(Eigen::Index rows, Eigen::Index cols, unsigned seed) {
  std::mt19937 rng(seed);
  std::normal_distribution<double> dist(0.0, 1.0);
  MatrixXd m(rows, cols);
  for (Eigen::Index i = 0; i < m.size(); ++i) m.data()[i] = dist(rng);
  return m;
}

// A yaw-like system: 2 states (poles 0.9 +- 0.3i), inputs [current; velocity], one output.
endohaptics::model::DynamicStateSpace<> yaw_like_system(int inputs) {
  MatrixXd B(2, inputs);
  B.col(0) << 1.0, 0.4;
  if (inputs > 1) B.col(1) << -0.2, 0.3;
  return {MatrixXd{{0.9, 0.3}, {-0.3, 0.9}}, B, MatrixXd{{1.0, -0.5}}, MatrixXd::Zero(1, inputs),
          1.0};
}

MatrixXd add_noise(const MatrixXd& y, double relative, unsigned seed) {
  const double sd = std::sqrt((y.array() - y.mean()).square().mean());
  return y + relative * sd * gaussian(y.rows(), y.cols(), seed);
}

}  // namespace

TEST_CASE("a known input dead zone (+-0.3) is recovered with the linear part, fit >= 90 %") {
  const auto g = yaw_like_system(1);
  const MatrixXd u = uniform(1500, 1, 1.0, 1);
  const std::vector<id::StaticMap> truth{{id::StaticMapKind::deadzone, -0.3, 0.3}};
  const MatrixXd y0 = id::simulate(g, id::apply_maps(truth, u), VectorXd::Zero(2));
  const MatrixXd y = add_noise(y0, 0.02, 2);  // 2 % output noise

  const id::HammersteinWienerFit fit = id::fit_hammerstein_wiener(u, y);  // order automatic
  REQUIRE(fit.input.size() == 1);
  CHECK(fit.input[0].kind == id::StaticMapKind::deadzone);
  CHECK(fit.input[0].upper == doctest::Approx(0.3).epsilon(0.02 / 0.3));
  CHECK(fit.input[0].lower == -fit.input[0].upper);
  CHECK(fit.linear.order == 2);
  CHECK(fit.fit[0] >= 90.0);
  // Against the noise-free output the model is near exact.
  CHECK(id::nrmse_fit(y0, id::simulate(fit, u, fit.linear.state_space.state()))[0] > 97.0);
  // A linear model alone does markedly worse on the same data.
  CHECK(id::compare(id::identify(u, y), u, y).fit[0] < fit.fit[0] - 3.0);
  CHECK(fit.evaluations > 40);
}

TEST_CASE("yaw-like 2-input system: dead zone on the current only (0.21 A), velocity linear") {
  const auto g = yaw_like_system(2);
  MatrixXd u(2000, 2);
  u.col(0) = uniform(2000, 1, 0.8, 11);  // current, A
  u.col(1) = uniform(2000, 1, 3.0, 12);  // velocity, rad/s
  const std::vector<id::StaticMap> truth{{id::StaticMapKind::deadzone, -0.21, 0.21}, {}};
  const MatrixXd y =
      add_noise(id::simulate(g, id::apply_maps(truth, u), VectorXd::Zero(2)), 0.02, 13);
  id::HammersteinWienerFitOptions options;
  options.input_kind = {id::StaticMapKind::deadzone, id::StaticMapKind::none};
  options.linear.order = 2;
  options.linear.estimate_d = false;  // like the appendix C models
  options.linear.sample_time = 0.02;
  const auto fit = id::fit_hammerstein_wiener(u, y, options);
  CHECK(fit.input[0].upper == doctest::Approx(0.21).epsilon(0.02 / 0.21));
  CHECK(fit.input[1].kind == id::StaticMapKind::none);
  CHECK(fit.fit[0] >= 90.0);
  CHECK(fit.linear.state_space.D().isZero(0.0));

  // As the real-time type (the same type as the yaw preset): steps like simulate().
  auto hw = id::to_hammerstein_wiener<2, 2, 1>(fit);
  CHECK(hw.input_nonlinearity().channel(0).upper() == fit.input[0].upper);
  CHECK(hw.input_nonlinearity().channel(1).upper() == 0.0);
  CHECK(hw.linear().sample_time() == 0.02);
  const MatrixXd y_hat = id::simulate(fit, u, fit.linear.state_space.state());
  for (int k = 0; k < 100; ++k) {
    REQUIRE(hw.step(u.row(k).transpose())(0) == doctest::Approx(y_hat(k, 0)).epsilon(1e-12));
  }
  CHECK_THROWS_AS((void)(id::to_hammerstein_wiener<2, 1, 1>(fit)), Error);
  CHECK_THROWS_AS(
      (void)(id::to_hammerstein_wiener<2, 2, 1, double, endohaptics::model::Saturation<double>>(
          fit)),
      Error);
}

TEST_CASE("an asymmetric dead zone [-0.15, 0.35] with symmetric = false") {
  const auto g = yaw_like_system(1);
  const MatrixXd u = uniform(1500, 1, 1.0, 21);
  const std::vector<id::StaticMap> truth{{id::StaticMapKind::deadzone, -0.15, 0.35}};
  const MatrixXd y =
      add_noise(id::simulate(g, id::apply_maps(truth, u), VectorXd::Zero(2)), 0.01, 22);
  id::HammersteinWienerFitOptions options;
  options.symmetric = false;
  options.linear.order = 2;
  const auto fit = id::fit_hammerstein_wiener(u, y, options);
  CHECK(fit.input[0].upper == doctest::Approx(0.35).epsilon(0.02 / 0.35));
  CHECK(fit.input[0].lower == doctest::Approx(-0.15).epsilon(0.02 / 0.15));
  CHECK(fit.fit[0] >= 90.0);
}

TEST_CASE("input saturation and output saturation are found, none is added when absent") {
  const auto g = yaw_like_system(1);
  const MatrixXd u = uniform(1500, 1, 1.0, 31);
  // Input clipped at +-0.6; output clipped at [-2.0, 1.5].
  const std::vector<id::StaticMap> f{{id::StaticMapKind::saturation, -0.6, 0.6}};
  const std::vector<id::StaticMap> h{{id::StaticMapKind::saturation, -2.0, 1.5}};
  const MatrixXd linear_y = id::simulate(g, id::apply_maps(f, u), VectorXd::Zero(2));
  REQUIRE(linear_y.maxCoeff() > 1.8);  // the output limits are active
  REQUIRE(linear_y.minCoeff() < -2.3);
  const MatrixXd y = id::apply_maps(h, linear_y);
  id::HammersteinWienerFitOptions options;
  options.input_kind = {id::StaticMapKind::saturation};
  options.output_saturation = true;
  options.linear.order = 2;
  const auto fit = id::fit_hammerstein_wiener(u, y, options);
  CHECK(fit.input[0].upper == doctest::Approx(0.6).epsilon(0.05 / 0.6));
  REQUIRE(fit.output[0].kind == id::StaticMapKind::saturation);
  CHECK(fit.output[0].upper == doctest::Approx(1.5).epsilon(0.1 / 1.5));
  CHECK(fit.output[0].lower == doctest::Approx(-2.0).epsilon(0.1 / 2.0));
  CHECK(fit.fit[0] >= 90.0);

  // A linear system: no output saturation kept, dead zone ~0.
  const MatrixXd y_linear = id::simulate(g, u, VectorXd::Zero(2));
  id::HammersteinWienerFitOptions plain;
  plain.output_saturation = true;
  plain.linear.order = 2;
  const auto linear_fit = id::fit_hammerstein_wiener(u, y_linear, plain);
  CHECK(linear_fit.output[0].kind == id::StaticMapKind::none);
  CHECK(linear_fit.input[0].upper < 0.01);
  CHECK(linear_fit.fit[0] > 99.9);
}

TEST_CASE("bad options throw Error naming the option") {
  const MatrixXd u = uniform(300, 1, 1.0, 41);
  const MatrixXd y = uniform(300, 1, 1.0, 42);
  id::HammersteinWienerFitOptions options;
  options.input_kind = {id::StaticMapKind::deadzone, id::StaticMapKind::none};
  CHECK_THROWS_WITH_AS((void)id::fit_hammerstein_wiener(u, y, options),
                       "fit_hammerstein_wiener: input_kind has 2 entries for 1 inputs", Error);
  options = {};
  options.grid_points = 2;
  CHECK_THROWS_WITH_AS((void)id::fit_hammerstein_wiener(u, y, options),
                       "fit_hammerstein_wiener: grid_points must be >= 3, got 2", Error);
  CHECK_THROWS_AS((void)id::apply_maps(std::vector<id::StaticMap>(2), u), Error);
}

}  // namespace identification_hammerstein_wiener_fit_test
