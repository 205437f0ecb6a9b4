#include <doctest/doctest.h>

#include <cmath>
#include <limits>
#include <random>
#include <string>

#include "endohaptics/identification/fit_metrics.hpp"
#include "endohaptics/identification/signal.hpp"
#include "endohaptics/identification/subspace.hpp"
#include "test_support.hpp"

// Identification whose result does not depend on the data's units. Before the
// fix, inputs scaled by 1e150 gave a 10.9 % fit (99.9 % unscaled) and fit metrics of data of
// 1e155 overflowed to NaN.
namespace identification_scaling_test {

using endohaptics::test::message_of;

namespace {

namespace id = endohaptics::identification;
using Eigen::MatrixXd;
using Eigen::VectorXd;

// x(k+1) = A x + B u, y = C x + D u: A = [1.5 -0.7; 1 0], B = [1 0.5; 0 -0.3], C = [0.5 0.3],
// D = [0.2 0] (the e2e test's system); u random levels held 1..8 samples, 0.5 % output noise.
id::DataSet second_order_data(Eigen::Index rows, unsigned seed) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> level(-1.0, 1.0);
  std::uniform_int_distribution<int> hold(1, 8);
  MatrixXd u(rows, 2);
  for (Eigen::Index c = 0; c < 2; ++c) {
    int left = 0;
    double value = 0.0;
    for (Eigen::Index k = 0; k < rows; ++k) {
      if (left == 0) {
        value = level(rng);
        left = hold(rng);
      }
      u(k, c) = value;
      --left;
    }
  }
  MatrixXd y(rows, 1);
  double x1 = 0.0;
  double x2 = 0.0;
  for (Eigen::Index k = 0; k < rows; ++k) {
    y(k, 0) = 0.5 * x1 + 0.3 * x2 + 0.2 * u(k, 0) + 0.005 * level(rng);
    const double n1 = 1.5 * x1 - 0.7 * x2 + u(k, 0) + 0.5 * u(k, 1);
    const double n2 = x1 - 0.3 * u(k, 1);
    x1 = n1;
    x2 = n2;
  }
  return {u, y};
}

double fit_of(const id::SubspaceModel& m, const id::DataSet& d) {
  return id::compare(m, d.u, d.y).fit[0];
}

}  // namespace

TEST_CASE("identify: inputs and outputs scaled by 1e150 or 1e-150 give the unscaled fit") {
  const id::DataSet data = second_order_data(2000, 7);
  id::SubspaceOptions options;
  options.order = 2;
  const id::SubspaceModel plain = id::identify(data.u, data.y, options);
  const double reference = fit_of(plain, data);
  REQUIRE(reference > 99.0);
  // Data of ordinary size is left as given (automatic); unit_rms scales it anyway.
  CHECK(plain.input_scale == VectorXd::Ones(2));
  CHECK(plain.output_scale == VectorXd::Ones(1));
  id::SubspaceOptions always = options;
  always.scaling = id::SubspaceOptions::Scaling::unit_rms;
  const id::SubspaceModel unit = id::identify(data.u, data.y, always);
  CHECK(unit.input_scale[0] == doctest::Approx(0.58).epsilon(0.05));
  CHECK(fit_of(unit, data) == doctest::Approx(reference).epsilon(1e-6));

  struct Case {
    double u_factor, y_factor;
  };
  for (const Case c : {Case{1e150, 1.0}, Case{1.0, 1e150}, Case{1e150, 1e150}, Case{1e-150, 1.0},
                       Case{1.0, 1e-150}, Case{1e150, 1e-150}}) {
    CAPTURE(c.u_factor);
    CAPTURE(c.y_factor);
    const id::DataSet scaled{data.u * c.u_factor, data.y * c.y_factor};
    const id::SubspaceModel m = id::identify(scaled.u, scaled.y, options);
    // The model works in the data's units: the same fit, the same poles, a scaled gain.
    CHECK(fit_of(m, scaled) == doctest::Approx(fit_of(unit, data)).epsilon(1e-9));
    CHECK(fit_of(m, scaled) == doctest::Approx(reference).epsilon(1e-3));
    CHECK(m.state_space.spectral_radius() ==
          doctest::Approx(unit.state_space.spectral_radius()).epsilon(1e-9));
    CHECK(m.input_scale[0] == doctest::Approx(unit.input_scale[0] * c.u_factor).epsilon(1e-12));
    const MatrixXd y_hat = id::simulate(m, scaled.u, VectorXd::Zero(2));
    const MatrixXd y_plain = id::simulate(unit, data.u, VectorXd::Zero(2));
    CHECK(((y_hat / c.y_factor) - y_plain).cwiseAbs().maxCoeff() <
          1e-6 * y_plain.cwiseAbs().maxCoeff());
  }
  // Each method, and automatic order selection, on the 1e150 data.
  const id::DataSet big{data.u * 1e150, data.y * 1e150};
  for (const id::Weighting w : {id::Weighting::n4sid, id::Weighting::moesp, id::Weighting::cva}) {
    id::SubspaceOptions automatic;
    automatic.weighting = w;
    const id::SubspaceModel m = id::identify(big.u, big.y, automatic);
    CHECK(m.order == 2);
    CHECK(fit_of(m, big) > 99.0);
  }
}

TEST_CASE("identify refuses non-finite data") {
  id::DataSet data = second_order_data(400, 3);
  data.u(10, 1) = std::numeric_limits<double>::infinity();
  CHECK(message_of([&] { (void)id::identify(data.u, data.y); }).find("not finite") !=
        std::string::npos);
  data.u(10, 1) = std::numeric_limits<double>::quiet_NaN();
  CHECK(message_of([&] { (void)id::identify(data.u, data.y); }).find("not finite") !=
        std::string::npos);
}

TEST_CASE("fit metrics of data near the overflow limit are those of the unscaled data") {
  const id::DataSet data = second_order_data(500, 5);
  const MatrixXd y = data.y;
  const MatrixXd y_hat = 0.9 * y + 0.01 * data.u.col(0);
  const double fit = id::nrmse_fit(y, y_hat)[0];
  const double r = id::correlation(y, y_hat)[0];
  const double e = id::rmse(y, y_hat)[0];
  for (const double factor : {1e155, 1e300, 1e-300}) {
    CAPTURE(factor);
    CHECK(id::nrmse_fit(y * factor, y_hat * factor)[0] == doctest::Approx(fit).epsilon(1e-12));
    CHECK(id::correlation(y * factor, y_hat * factor)[0] == doctest::Approx(r).epsilon(1e-12));
    CHECK(id::rmse(y * factor, y_hat * factor)[0] / factor == doctest::Approx(e).epsilon(1e-12));
  }
}

TEST_CASE("resample_uniform: a grid above max_samples is refused before it is allocated") {
  const VectorXd t = VectorXd::LinSpaced(100, 0.0, 99.0);
  const MatrixXd s = MatrixXd::Ones(100, 1);
  const std::string m = message_of([&] { (void)id::resample_uniform(t, s, 1e-9); });
  CHECK(m.find("more than the limit of 100000000") != std::string::npos);
  id::ResampleOptions small;
  small.max_samples = 50;
  CHECK(message_of([&] {
          (void)id::resample_uniform(t, s, 1.0, small);
        }).find("100 grid samples, more than the limit of 50") != std::string::npos);
  CHECK(id::resample_uniform(t, s, 1.0).segments.front().rows() == 100);
}

}  // namespace identification_scaling_test
