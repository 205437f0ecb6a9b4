//! @file
//! Force-feedback accuracy against the simulated rig's truth: both time series are put on one
//! uniform grid (linear interpolation over their common span), then NRMSE fit % (MATLAB's
//! definition, 100 (1 - ||y - yhat|| / ||y - mean y||)), Pearson correlation, RMS error, and the
//! delay of the estimate (the lag maximising the correlation). Configuration-time code. Units: s,
//! N.
#pragma once

#include <Eigen/Core>
#include <algorithm>
#include <cmath>
#include <cstddef>
#include <span>
#include <string>
#include <vector>

#include "endohaptics/core/error.hpp"
#include "endohaptics/model/fit_metric.hpp"

namespace endohaptics::sim {

//! One comparison. Fit and correlation are NaN when the truth is constant (no variation).
struct ForceAccuracy {
  std::size_t samples = 0;   //!< grid points compared
  double span = 0.0;         //!< s, common time span
  double fit_percent = 0.0;  //!< NRMSE fit %, at lag 0 (100 = perfect, 0 = as good as the mean)
  double correlation = 0.0;  //!< Pearson, at lag 0
  double rmse = 0.0;         //!< N, at lag 0
  double delay = 0.0;        //!< s, lag of the estimate behind the truth maximising correlation
  double fit_percent_at_delay = 0.0;  //!< NRMSE fit % once the delay is removed
  double correlation_at_delay = 0.0;  //!< Pearson once the delay is removed
  double truth_peak = 0.0;            //!< N, max |truth|
  double estimate_peak = 0.0;         //!< N, max |estimate|
};

namespace detail {

//! Linear interpolation of (t, y) at `grid` (t strictly increasing after the caller's check).
inline Eigen::VectorXd interpolate(std::span<const double> t, std::span<const double> y,
                                   const Eigen::VectorXd& grid) {
  Eigen::VectorXd out(grid.size());
  std::size_t j = 0;
  for (Eigen::Index i = 0; i < grid.size(); ++i) {
    const double g = grid[i];
    while (j + 2 < t.size() && t[j + 1] < g) ++j;
    const double t0 = t[j], t1 = t[j + 1];
    const double w = t1 > t0 ? std::clamp((g - t0) / (t1 - t0), 0.0, 1.0) : 0.0;
    out[i] = y[j] + w * (y[j + 1] - y[j]);
  }
  return out;
}

inline double pearson(const Eigen::VectorXd& a, const Eigen::VectorXd& b) {
  const Eigen::ArrayXd da = a.array() - a.mean(), db = b.array() - b.mean();
  const double denom = std::sqrt((da * da).sum() * (db * db).sum());
  return denom > 0.0 ? (da * db).sum() / denom : std::nan("");
}

inline void check_series(std::span<const double> t, std::span<const double> y, const char* what) {
  if (t.size() != y.size()) {
    ENDOHAPTICS_THROW(Error(std::string("force_accuracy: ") + what + " has " +
                            std::to_string(t.size()) + " times but " + std::to_string(y.size()) +
                            " values"));
  }
  if (t.size() < 2) {
    ENDOHAPTICS_THROW(Error(std::string("force_accuracy: ") + what + " has fewer than 2 samples"));
  }
  for (std::size_t i = 0; i < t.size(); ++i) {
    if (!std::isfinite(t[i]) || !std::isfinite(y[i])) {
      ENDOHAPTICS_THROW(Error(std::string("force_accuracy: ") + what + " sample " +
                              std::to_string(i) + " is not finite"));
    }
    if (i > 0 && !(t[i] > t[i - 1])) {
      ENDOHAPTICS_THROW(Error(std::string("force_accuracy: ") + what +
                              " times are not strictly increasing at sample " + std::to_string(i)));
    }
  }
}

}  // namespace detail

//! Compares `estimate` (t_est, f_est) with `truth` (t_truth, f_truth) on a grid of `step` s over
//! their common span; lags 0..max_delay are searched for the delay. Throws Error on series that
//! are unequal in length, shorter than 2, non-finite, not increasing, or do not overlap.
[[nodiscard]] inline ForceAccuracy force_accuracy(std::span<const double> t_truth,
                                                  std::span<const double> f_truth,
                                                  std::span<const double> t_est,
                                                  std::span<const double> f_est, double step = 1e-3,
                                                  double max_delay = 0.3) {
  detail::check_series(t_truth, f_truth, "truth");
  detail::check_series(t_est, f_est, "estimate");
  if (!(step > 0.0) || !std::isfinite(step) || !(max_delay >= 0.0) || !std::isfinite(max_delay)) {
    ENDOHAPTICS_THROW(Error("force_accuracy: step must be > 0 and max_delay >= 0"));
  }
  const double begin = std::max(t_truth.front(), t_est.front());
  const double end = std::min(t_truth.back(), t_est.back());
  const auto lag_max = static_cast<Eigen::Index>(std::floor(max_delay / step));
  const auto n = static_cast<Eigen::Index>(std::floor((end - begin) / step)) + 1;
  if (!(end > begin) || n < 2 * lag_max + 10) {
    ENDOHAPTICS_THROW(Error("force_accuracy: the truth and the estimate overlap for " +
                            std::to_string(std::max(0.0, end - begin)) + " s only"));
  }
  const Eigen::VectorXd grid =
      Eigen::VectorXd::LinSpaced(n, begin, begin + step * static_cast<double>(n - 1));
  const Eigen::VectorXd y = detail::interpolate(t_truth, f_truth, grid);
  const Eigen::VectorXd yhat = detail::interpolate(t_est, f_est, grid);

  ForceAccuracy a;
  a.samples = static_cast<std::size_t>(n);
  a.span = step * static_cast<double>(n - 1);
  a.fit_percent = model::fit_percent(y, yhat);
  a.correlation = detail::pearson(y, yhat);
  a.rmse = std::sqrt((y - yhat).squaredNorm() / static_cast<double>(n));
  a.truth_peak = y.cwiseAbs().maxCoeff();
  a.estimate_peak = yhat.cwiseAbs().maxCoeff();
  // Estimate lags the truth by k samples: compare y[0 .. n-k) with yhat[k .. n).
  Eigen::Index best = 0;
  double best_corr = -2.0;
  const Eigen::Index m = n - lag_max;
  for (Eigen::Index k = 0; k <= lag_max; ++k) {
    const double c = detail::pearson(y.head(m), yhat.segment(k, m));
    if (std::isfinite(c) && c > best_corr) {
      best_corr = c;
      best = k;
    }
  }
  a.delay = step * static_cast<double>(best);
  a.correlation_at_delay = best_corr >= -1.0 ? best_corr : std::nan("");
  a.fit_percent_at_delay = model::fit_percent(y.head(m), yhat.segment(best, m));
  return a;
}

}  // namespace endohaptics::sim
