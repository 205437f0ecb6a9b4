//! @file
//! Goodness of fit of a model output: MATLAB's NRMSE fit, 100 (1 - ||y - yhat|| / ||y - mean y||)
//! in %, per output column; Pearson correlation; RMSE (output units); the delay of an estimate
//! (lag of the cross-correlation peak, samples). `compare` simulates a model like MATLAB's compare
//! (x0 by least squares or zero) and reports fit, correlation and RMSE.
//! Each is computed on the columns divided by their largest magnitude, so any finite data works.
//! Configuration time (validation tools): dynamic sizes, throws Error on mismatched data.
#pragma once

#include <Eigen/Core>
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <limits>
#include <string>
#include <string_view>
#include "endohaptics/core/separate_compilation.hpp"

#include "endohaptics/core/error.hpp"
#include "endohaptics/identification/subspace.hpp"
#include "endohaptics/model/fit_metric.hpp"

namespace endohaptics::identification {

namespace detail::fit {

//! Throws Error unless y and yhat are both N x ny with N >= 1 and finite.
ENDOHAPTICS_DECL void check_pair(const Eigen::MatrixXd& y, const Eigen::MatrixXd& y_hat,
                                 const char* where);

//! Largest magnitude in column i of y and y_hat (1 when both are all zero): the metrics divide
//! both columns by it first, so that data of 1e150 does not overflow their sums of squares.
ENDOHAPTICS_DECL double column_scale(const Eigen::MatrixXd& y, const Eigen::MatrixXd& y_hat,
                                     Eigen::Index i);

}  // namespace detail::fit

//! NRMSE fit per output, %: model::fit_percent of each column (100 (1 - ||y_i - yhat_i|| /
//! ||y_i - mean(y_i)||), MATLAB goodnessOfFit 'NRMSE' as 100 (1 - cost), what compare prints).
//! 100 is perfect, 0 is as good as the mean, negative is worse; -Inf when y_i is constant and
//! yhat_i differs from it, 100 when equal.
//! y and yhat are N x ny. Throws Error on mismatched sizes, no samples, non-finite values.
[[nodiscard]] ENDOHAPTICS_DECL Eigen::VectorXd nrmse_fit(const Eigen::MatrixXd& y,
                                                         const Eigen::MatrixXd& y_hat);

//! Root-mean-square error per output, output units: sqrt(mean((y_i - yhat_i)^2)).
//! Throws Error as `nrmse_fit`.
[[nodiscard]] ENDOHAPTICS_DECL Eigen::VectorXd rmse(const Eigen::MatrixXd& y,
                                                    const Eigen::MatrixXd& y_hat);

//! Pearson correlation per output, in [-1, 1]; NaN when either column is constant.
//! Throws Error as `nrmse_fit`.
[[nodiscard]] ENDOHAPTICS_DECL Eigen::VectorXd correlation(const Eigen::MatrixXd& y,
                                                           const Eigen::MatrixXd& y_hat);

//! Delay of y_hat behind y per output, in samples: the lag L in [-max_lag, max_lag] that maximises
//! the cross-correlation sum_k (y[k] - mean y) (y_hat[k + L] - mean y_hat) over the overlap,
//! divided by the overlap length (so that long lags are not penalised for fewer terms).
//! Positive: the estimate lags the truth. 0 when either column is constant. The smallest |L|
//! wins a tie. O(N max_lag). Throws Error as `nrmse_fit` or when max_lag < 0.
[[nodiscard]] ENDOHAPTICS_DECL Eigen::VectorXd cross_correlation_lag(const Eigen::MatrixXd& y,
                                                                     const Eigen::MatrixXd& y_hat,
                                                                     Eigen::Index max_lag);

//! How `compare` sets the initial state (MATLAB compareOptions InitialCondition).
enum class InitialState : std::uint8_t {
  estimate = 0,  //!< least squares on the compared data ('e', MATLAB's default)
  zero,          //!< x0 = 0 ('z')
};

//! What `compare` returns: the simulated output and its fit to the measured one.
struct Comparison {
  Eigen::MatrixXd y_hat;        //!< simulated output, N x ny
  Eigen::VectorXd x0;           //!< initial state used
  Eigen::VectorXd fit;          //!< NRMSE fit per output, %
  Eigen::VectorXd rmse;         //!< per output, output units
  Eigen::VectorXd correlation;  //!< per output
};

//! Simulates `model` on u (N x nu) from x0 (estimated or zero) and compares with y (N x ny),
//! like MATLAB compare. Throws Error on mismatched sizes or non-finite data.
template <IdentifiableModel M>
[[nodiscard]] Comparison compare(const M& model, const Eigen::MatrixXd& u, const Eigen::MatrixXd& y,
                                 InitialState initial_state = InitialState::estimate) {
  Comparison result;
  const auto matrices = detail::subspace::matrices_of(model);
  if (initial_state == InitialState::estimate) {
    result.x0 = detail::subspace::estimate_initial_state(matrices, u, y, "compare");
  } else {
    detail::subspace::check_input(matrices, u, "compare");
    result.x0 = Eigen::VectorXd::Zero(matrices.A.rows());
  }
  result.y_hat = detail::subspace::simulate(matrices, u, result.x0);
  result.fit = nrmse_fit(y, result.y_hat);
  result.rmse = rmse(y, result.y_hat);
  result.correlation = correlation(y, result.y_hat);
  return result;
}

}  // namespace endohaptics::identification

#if !defined(ENDOHAPTICS_SEPARATE_COMPILATION)
#include "endohaptics/identification/impl/fit_metrics.ipp"
#endif
