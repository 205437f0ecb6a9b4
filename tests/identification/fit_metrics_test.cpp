#include "endohaptics/identification/fit_metrics.hpp"

#include <doctest/doctest.h>

#include <cmath>
#include <limits>

#include "endohaptics/model/presets_2016.hpp"

namespace identification_fit_metrics_test {

namespace {

namespace id = endohaptics::identification;
using Eigen::MatrixXd;
using Eigen::VectorXd;
using endohaptics::Error;

}  // namespace

TEST_CASE("NRMSE fit, RMSE and correlation per output, worked out by hand") {
  // Column 0: y = 1 2 3 4, yhat = 1 2 3 5: ||e|| = 1, ||y - 2.5|| = sqrt(5):
  //   fit = 100 (1 - 1/sqrt(5)) = 55.27864045, rmse = sqrt(1/4) = 0.5,
  //   r = 6.5 / sqrt(5 x 8.75) = 0.98270763 (numpy: np.corrcoef([1,2,3,4],[1,2,3,5])[0,1]).
  // Column 1: yhat = the mean of y: fit 0, correlation NaN (constant yhat).
  // Column 2: yhat = y: fit 100, rmse 0, r 1.
  MatrixXd y(4, 3);
  y << 1, 1, 7, 2, 2, -1, 3, 3, 0.5, 4, 4, 2;
  MatrixXd y_hat(4, 3);
  y_hat << 1, 2.5, 7, 2, 2.5, -1, 3, 2.5, 0.5, 5, 2.5, 2;
  const VectorXd fit = id::nrmse_fit(y, y_hat);
  CHECK(fit[0] == doctest::Approx(55.27864045).epsilon(1e-9));
  CHECK(fit[1] == doctest::Approx(0.0));
  CHECK(fit[2] == 100.0);
  const VectorXd e = id::rmse(y, y_hat);
  CHECK(e[0] == doctest::Approx(0.5));
  CHECK(e[1] == doctest::Approx(std::sqrt(5.0 / 4.0)));
  CHECK(e[2] == 0.0);
  const VectorXd r = id::correlation(y, y_hat);
  CHECK(r[0] == doctest::Approx(0.98270763).epsilon(1e-8));
  CHECK(std::isnan(r[1]));
  CHECK(r[2] == doctest::Approx(1.0));
}

TEST_CASE("a constant measured output: fit 100 when matched, -Inf otherwise") {
  const MatrixXd y = MatrixXd::Constant(5, 1, 3.0);
  CHECK(id::nrmse_fit(y, y)[0] == 100.0);
  CHECK(id::nrmse_fit(y, MatrixXd::Constant(5, 1, 3.5))[0] ==
        -std::numeric_limits<double>::infinity());
}

TEST_CASE("compare: x0 estimated (MATLAB's default) or zero") {
  // y(k+1) = 0.5 y(k) + u(k) from x0 = 2 with u = 0: y = 2 1 0.5 0.25.
  // x0 = 0 predicts 0: fit = 100 (1 - ||y|| / ||y - mean y||) = -71.94539072 (numpy, same
  // formula: y = np.array([2, 1, .5, .25]); 100 * (1 - norm(y) / norm(y - y.mean()))).
  const endohaptics::model::DynamicStateSpace<> m(
      MatrixXd::Constant(1, 1, 0.5), MatrixXd::Constant(1, 1, 1.0), MatrixXd::Constant(1, 1, 1.0),
      MatrixXd::Zero(1, 1), 1.0);
  const MatrixXd u = MatrixXd::Zero(4, 1);
  MatrixXd y(4, 1);
  y << 2, 1, 0.5, 0.25;
  const id::Comparison estimated = id::compare(m, u, y);
  CHECK(estimated.x0[0] == doctest::Approx(2.0).epsilon(1e-12));
  CHECK(estimated.fit[0] == doctest::Approx(100.0).epsilon(1e-10));
  CHECK(estimated.rmse[0] < 1e-12);
  const id::Comparison zero = id::compare(m, u, y, id::InitialState::zero);
  CHECK(zero.x0[0] == 0.0);
  CHECK(zero.y_hat.isZero(0.0));
  CHECK(zero.fit[0] == doctest::Approx(-71.94539072).epsilon(1e-9));
}

TEST_CASE("compare takes a fixed-size StateSpace: the yaw preset reproduces itself") {
  auto yaw = endohaptics::model::yaw_force_2016();
  Eigen::Matrix<double, 6, 1> x0;
  x0 << 0.1, -0.2, 0.05, 0.0, 0.3, -0.1;
  MatrixXd u(400, 2);
  for (int k = 0; k < 400; ++k) {
    u(k, 0) = 0.3 * std::sin(0.05 * k);   // current, A
    u(k, 1) = 2.0 * std::cos(0.031 * k);  // velocity, rad/s
  }
  const MatrixXd y = id::simulate(yaw, u, x0);
  // simulate() agrees with stepping the preset itself.
  yaw.reset(x0);
  for (int k = 0; k < 400; ++k) {
    REQUIRE(yaw.step(u.row(k).transpose())(0) == doctest::Approx(y(k, 0)).epsilon(1e-12));
  }
  yaw.reset();
  const id::Comparison c = id::compare(yaw, u, y);
  CHECK(c.fit[0] > 99.9999);
  CHECK(c.correlation[0] == doctest::Approx(1.0).epsilon(1e-9));
  CHECK((c.x0 - x0).norm() < 1e-6 * x0.norm() + 1e-9);
}

TEST_CASE("metrics refuse mismatched, empty or non-finite data") {
  const MatrixXd a = MatrixXd::Ones(5, 2);
  CHECK_THROWS_WITH_AS((void)id::nrmse_fit(a, MatrixXd::Ones(4, 2)),
                       "nrmse_fit: y is 5 x 2, yhat 4 x 2", Error);
  CHECK_THROWS_AS((void)id::rmse(MatrixXd(0, 1), MatrixXd(0, 1)), Error);
  MatrixXd bad = a;
  bad(2, 1) = std::numeric_limits<double>::infinity();
  CHECK_THROWS_WITH_AS((void)id::correlation(a, bad), "correlation: yhat(2,1) is not finite (inf)",
                       Error);
  const endohaptics::model::DynamicStateSpace<> m(MatrixXd::Zero(1, 1), MatrixXd::Zero(1, 1),
                                                  MatrixXd::Zero(1, 1), MatrixXd::Zero(1, 1), 1.0);
  CHECK_THROWS_AS((void)id::compare(m, MatrixXd::Zero(5, 2), MatrixXd::Zero(5, 1)), Error);
  CHECK_THROWS_AS((void)id::compare(m, MatrixXd::Zero(5, 1), MatrixXd::Zero(4, 1)), Error);
}

}  // namespace identification_fit_metrics_test
