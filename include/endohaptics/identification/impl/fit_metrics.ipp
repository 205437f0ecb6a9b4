//! @file
//! Function bodies of identification/fit_metrics.hpp: included at its end (header-only, the
//! default), or compiled once with ENDOHAPTICS_SEPARATE_COMPILATION
//! (core/separate_compilation.hpp).
#pragma once

#include "endohaptics/identification/fit_metrics.hpp"

namespace endohaptics::identification {
namespace detail::fit {

ENDOHAPTICS_DECL void check_pair(const Eigen::MatrixXd& y, const Eigen::MatrixXd& y_hat,
                                 const char* where) {
  using subspace::fail;
  using subspace::idx;
  if (y.rows() != y_hat.rows() || y.cols() != y_hat.cols()) {
    fail(std::string(where) + ": y is " + idx(y.rows()) + " x " + idx(y.cols()) + ", yhat " +
         idx(y_hat.rows()) + " x " + idx(y_hat.cols()));
  }
  if (y.rows() < 1) fail(std::string(where) + ": no samples");
  subspace::require_finite(y, std::string(where) + ": y");
  subspace::require_finite(y_hat, std::string(where) + ": yhat");
}

ENDOHAPTICS_DECL double column_scale(const Eigen::MatrixXd& y, const Eigen::MatrixXd& y_hat,
                                     Eigen::Index i) {
  const double peak = std::max(y.col(i).cwiseAbs().maxCoeff(), y_hat.col(i).cwiseAbs().maxCoeff());
  return peak > 0.0 ? peak : 1.0;
}
}  // namespace detail::fit
}  // namespace endohaptics::identification

namespace endohaptics::identification {

ENDOHAPTICS_DECL Eigen::VectorXd nrmse_fit(const Eigen::MatrixXd& y, const Eigen::MatrixXd& y_hat) {
  detail::fit::check_pair(y, y_hat, "nrmse_fit");
  Eigen::VectorXd fit(y.cols());
  for (Eigen::Index i = 0; i < y.cols(); ++i) fit[i] = model::fit_percent(y.col(i), y_hat.col(i));
  return fit;
}

ENDOHAPTICS_DECL Eigen::VectorXd rmse(const Eigen::MatrixXd& y, const Eigen::MatrixXd& y_hat) {
  detail::fit::check_pair(y, y_hat, "rmse");
  Eigen::VectorXd r(y.cols());
  for (Eigen::Index i = 0; i < y.cols(); ++i) {
    const double scale = detail::fit::column_scale(y, y_hat, i);
    const double mean_square =
        ((y.col(i) - y_hat.col(i)) / scale).squaredNorm() / static_cast<double>(y.rows());
    r[i] = scale * std::sqrt(mean_square);
  }
  return r;
}

ENDOHAPTICS_DECL Eigen::VectorXd correlation(const Eigen::MatrixXd& y,
                                             const Eigen::MatrixXd& y_hat) {
  detail::fit::check_pair(y, y_hat, "correlation");
  Eigen::VectorXd r(y.cols());
  for (Eigen::Index i = 0; i < y.cols(); ++i) {
    const double scale = detail::fit::column_scale(y, y_hat, i);
    const Eigen::VectorXd ys = y.col(i) / scale;
    const Eigen::VectorXd ys_hat = y_hat.col(i) / scale;
    const Eigen::VectorXd a = ys.array() - ys.mean();
    const Eigen::VectorXd b = ys_hat.array() - ys_hat.mean();
    const double denominator = a.norm() * b.norm();
    r[i] = denominator > 0.0 ? a.dot(b) / denominator : std::numeric_limits<double>::quiet_NaN();
  }
  return r;
}

ENDOHAPTICS_DECL Eigen::VectorXd cross_correlation_lag(const Eigen::MatrixXd& y,
                                                       const Eigen::MatrixXd& y_hat,
                                                       Eigen::Index max_lag) {
  detail::fit::check_pair(y, y_hat, "cross_correlation_lag");
  if (max_lag < 0) detail::subspace::fail("cross_correlation_lag: max_lag must be >= 0");
  const Eigen::Index n = y.rows();
  max_lag = std::min(max_lag, n - 1);
  Eigen::VectorXd lag = Eigen::VectorXd::Zero(y.cols());
  for (Eigen::Index i = 0; i < y.cols(); ++i) {
    const double scale = detail::fit::column_scale(y, y_hat, i);
    const Eigen::VectorXd a = (y.col(i) / scale).array() - (y.col(i) / scale).mean();
    const Eigen::VectorXd b = (y_hat.col(i) / scale).array() - (y_hat.col(i) / scale).mean();
    if (!(a.norm() > 0.0) || !(b.norm() > 0.0)) continue;
    double best = -std::numeric_limits<double>::infinity();
    for (Eigen::Index m = 0; m <= 2 * max_lag; ++m) {
      // 0, 1, -1, 2, -2, ...: the smallest |L| wins a tie.
      const Eigen::Index l = (m % 2 == 1) ? (m + 1) / 2 : -(m / 2);
      const Eigen::Index overlap = n - (l < 0 ? -l : l);
      const double r =
          l >= 0 ? a.head(overlap).dot(b.tail(overlap)) : a.tail(overlap).dot(b.head(overlap));
      const double value = r / static_cast<double>(overlap);
      if (value > best) {
        best = value;
        lag[i] = static_cast<double>(l);
      }
    }
  }
  return lag;
}

}  // namespace endohaptics::identification
