//! @file
//! Identification of one joint's friction constants (worksheet 5.2, eqs. 5.4-5.7: Ks, Kc, F_mu of
//! model::JointFriction) from a free-movement log, by a Huber fit per direction and the largest
//! motion-onset current. Time in s, encoder ticks, currents in A, velocities in rad/s (motor side),
//! F_mu in A s/rad. Configuration time: allocates, throws Error. See docs/models/friction_model.md.
#pragma once

#include <Eigen/Core>
#include <algorithm>
#include <array>
#include <cmath>
#include <cstddef>
#include <limits>
#include <numbers>
#include <span>
#include <string>
#include <string_view>
#include <utility>
#include <vector>
#include "endohaptics/core/separate_compilation.hpp"

#include "endohaptics/core/error.hpp"
#include "endohaptics/core/median.hpp"
#include "endohaptics/identification/signal.hpp"
#include "endohaptics/model/friction_model.hpp"

namespace endohaptics::identification {

//! Settings of `identify_friction`; defaults suit the 2016 friction logs (~100 Hz, ticks, A).
struct FrictionIdentificationOptions {
  //! Encoder ticks -> rad after gearing: 2 pi / 76000, the quantum of the sbRIO's "measured
  //! position" in the 2016 logs (8.26734e-5 rad, to 1 ppm), i.e. 2048 counts/turn x 37.11.
  double radians_per_tick = 2.0 * std::numbers::pi / 76000.0;
  double grid_period = 0.01;          //!< resampling period, s (the logs' median step)
  double max_gap = 0.05;              //!< longer time steps split the log into segments, s
  double standstill_velocity = 0.01;  //!< |omega| <= this is standstill, rad/s
  double moving_velocity = 0.05;      //!< |omega| > this is sliding (used in the fit), rad/s
  double min_standstill = 0.2;        //!< standstill needed before a motion onset counts, s
  double onset_confirm = 0.1;         //!< after leaving standstill, |omega| must pass
                                      //!< moving_velocity within this time, s
  double onset_window = 0.05;         //!< onset current: median over [onset - 1 step, + this), s
  std::size_t min_fit_samples = 20;   //!< fewer sliding samples in a direction: no fit
  double huber_k = 1.345;             //!< Huber tuning constant, in robust standard deviations
};

//! Affine fit |current| = Kc + F_mu |omega| over the sliding samples of one direction.
struct FrictionDirectionFit {
  double coulomb_level = std::numeric_limits<double>::quiet_NaN();  //!< Kc, A (NaN: no fit)
  double viscous_gain = std::numeric_limits<double>::quiet_NaN();   //!< F_mu, A s/rad
  std::size_t samples = 0;  //!< sliding grid samples in this direction
  //! True when the fit succeeded (`coulomb_level` is finite).
  [[nodiscard]] bool valid() const noexcept { return std::isfinite(coulomb_level); }
};

//! What `identify_friction` found, with the bookkeeping of what it used and dropped.
struct FrictionIdentification {
  model::JointFriction<double>
      joint;                      //!< Ks (NaN if no onset), Kc, F_mu (sample-weighted over fits)
  FrictionDirectionFit positive;  //!< omega > 0 (increasing ticks)
  FrictionDirectionFit negative;  //!< omega < 0
  std::vector<double> onset_currents;  //!< |current| at each motion onset, A
  //! +1 when positive current moves the encoder count up, -1 when it moves it down.
  int current_sign = 1;
  std::size_t samples_in = 0;              //!< rows given
  std::size_t dropped_non_finite = 0;      //!< rows with NaN/Inf time, position or current
  std::size_t dropped_time_order = 0;      //!< rows whose time is not after the previous kept one
  std::size_t gaps = 0;                    //!< time steps > max_gap (segment boundaries)
  std::size_t dropped_short_segments = 0;  //!< rows in segments too short to differentiate
  std::size_t grid_samples = 0;            //!< resampled points with a velocity
  std::size_t moving_samples = 0;          //!< of which sliding (|omega| > moving_velocity)
};

namespace detail::friction {

using endohaptics::detail::median;

//! Huber M-estimate of y = a + b x by iteratively reweighted least squares; scale from the
//! median absolute deviation of the residuals (1.4826 MAD). Returns {a, b}.
ENDOHAPTICS_DECL std::array<double, 2> huber_line(const std::vector<double>& x,
                                                  const std::vector<double>& y, double k);

ENDOHAPTICS_DECL void require_positive(double value, std::string_view name);

}  // namespace detail::friction

//! Estimates Ks, Kc, F_mu of one joint from a free-movement log: time [s], encoder ticks,
//! motor current [A], one row per sample. Procedure (docs/models/friction_model.md): drop
//! non-finite rows and non-increasing times; split at gaps > max_gap; resample each segment
//! linearly on a grid_period grid; omega by central difference; Kc and F_mu by a Huber fit of
//! |current| against |omega| over sliding samples, per direction; Ks = the largest |current| at
//! a motion onset after >= min_standstill of standstill. Throws Error when the arrays differ in
//! length, an option is invalid, or no direction has min_fit_samples sliding samples.
[[nodiscard]] ENDOHAPTICS_DECL FrictionIdentification identify_friction(
    std::span<const double> time, std::span<const double> ticks, std::span<const double> current,
    const FrictionIdentificationOptions& options = {});

}  // namespace endohaptics::identification

#if !defined(ENDOHAPTICS_SEPARATE_COMPILATION)
#include "endohaptics/identification/impl/friction_fit.ipp"
#endif
