//! @file
//! The NRMSE fit in percent of an estimate against a measured signal, once for the library:
//! 100 (1 - ||y - yhat|| / ||y - mean(y)||) (MATLAB goodnessOfFit 'NRMSE' as 100 (1 - cost), what
//! compare prints). Used by identification (nrmse_fit, compare), the joint-model fits and the
//! force report. Units: none (percent).
#pragma once

#include <Eigen/Core>
#include <algorithm>
#include <cmath>
#include <limits>

namespace endohaptics::model {

//! NRMSE fit of `y_hat` against `y`, %: 100 is perfect, 0 as good as the mean, negative worse.
//! Edge cases, defined: NaN when the sizes differ, there are no samples or a value is not finite;
//! when `y` is constant, 100 if `y_hat` equals it and -Inf otherwise. Both signals are divided
//! by their largest magnitude first, so that data of 1e150 does not overflow the sums of
//! squares. Allocates (two scaled copies): not for the real-time path.
[[nodiscard]] inline double fit_percent(const Eigen::Ref<const Eigen::VectorXd>& y,
                                        const Eigen::Ref<const Eigen::VectorXd>& y_hat) {
  if (y.size() != y_hat.size() || y.size() < 1 || !y.allFinite() || !y_hat.allFinite()) {
    return std::numeric_limits<double>::quiet_NaN();
  }
  const double peak = std::max(y.cwiseAbs().maxCoeff(), y_hat.cwiseAbs().maxCoeff());
  const double scale = peak > 0.0 ? peak : 1.0;
  const Eigen::VectorXd a = y / scale;
  const Eigen::VectorXd b = y_hat / scale;
  const double error = (a - b).norm();
  const double spread = (a.array() - a.mean()).matrix().norm();
  if (spread > 0.0) return 100.0 * (1.0 - error / spread);
  return error == 0.0 ? 100.0 : -std::numeric_limits<double>::infinity();
}

}  // namespace endohaptics::model
