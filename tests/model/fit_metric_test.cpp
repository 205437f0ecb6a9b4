// model::fit_percent, the one NRMSE fit of the library: its value and every edge case.
#include <doctest/doctest.h>

#include <Eigen/Core>
#include <cmath>
#include <endohaptics/model/fit_metric.hpp>
#include <limits>

namespace model_fit_metric_test {

namespace md = endohaptics::model;

TEST_CASE("fit_percent: 100 (1 - ||y - yhat|| / ||y - mean y||) and its defined edge cases") {
  const Eigen::VectorXd y = (Eigen::VectorXd(4) << 1.0, 2.0, 3.0, 4.0).finished();
  CHECK(md::fit_percent(y, y) == 100.0);
  // The mean is as good as the mean: 0 %.
  CHECK(md::fit_percent(y, Eigen::VectorXd::Constant(4, 2.5)) == doctest::Approx(0.0));
  // ||y - yhat|| = 1 (one sample off by 1), ||y - mean|| = sqrt(5): 100 (1 - 1/sqrt(5)).
  Eigen::VectorXd off = y;
  off[2] += 1.0;
  CHECK(md::fit_percent(y, off) == doctest::Approx(100.0 * (1.0 - 1.0 / std::sqrt(5.0))));
  // Scale-free, and no overflow at 1e150 (the squares would be 1e300 and more).
  CHECK(md::fit_percent(1e150 * y, 1e150 * off) == doctest::Approx(md::fit_percent(y, off)));
  // A constant truth: 100 when matched exactly, -Inf otherwise.
  const Eigen::VectorXd flat = Eigen::VectorXd::Constant(4, 3.0);
  CHECK(md::fit_percent(flat, flat) == 100.0);
  CHECK(md::fit_percent(flat, y) == -std::numeric_limits<double>::infinity());
  CHECK(md::fit_percent(Eigen::VectorXd::Zero(3), Eigen::VectorXd::Zero(3)) == 100.0);
  // No samples, other sizes, NaN or Inf anywhere: NaN.
  CHECK(std::isnan(md::fit_percent(Eigen::VectorXd(), Eigen::VectorXd())));
  CHECK(std::isnan(md::fit_percent(y, y.head(3))));
  Eigen::VectorXd bad = y;
  bad[1] = std::numeric_limits<double>::quiet_NaN();
  CHECK(std::isnan(md::fit_percent(y, bad)));
  CHECK(std::isnan(md::fit_percent(bad, y)));
  bad[1] = -std::numeric_limits<double>::infinity();
  CHECK(std::isnan(md::fit_percent(y, bad)));
}

}  // namespace model_fit_metric_test
