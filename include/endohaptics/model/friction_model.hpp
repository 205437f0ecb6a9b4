//! @file
//! Per-joint EndoWrist friction in the motor-current domain (worksheet 5.2, eqs. 5.4-5.7,
//! table 5.2): viscous F_mu*omega + Coulomb sign(omega)*Kc while sliding, static Ks at standstill;
//! the 5.2.3 gate that feeds an estimated force back only once the current overcomes friction;
//! and identification of Ks, Kc, F_mu from free-movement logs. Currents in A, velocities in rad/s
//! (motor side, after gearing), F_mu in A s/rad. See docs/models/friction_model.md.
#pragma once

#include <Eigen/Core>
#include <algorithm>
#include <array>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <limits>
#include <numbers>
#include <span>
#include <string>
#include <string_view>
#include <type_traits>
#include <utility>
#include <vector>

#include "endohaptics/core/error.hpp"
#include "endohaptics/core/median.hpp"

namespace endohaptics::model {

//! Outcome of a per-tick friction call. Joints with bad data are handled, never skipped silently.
enum class FrictionStatus : std::uint8_t {
  ok = 0,
  non_finite_input,  //!< NaN/Inf on some joint: its gate is closed and its outputs are 0
};

//! Human-readable name of a status, for logs.
[[nodiscard]] constexpr std::string_view to_string(FrictionStatus status) noexcept {
  switch (status) {
    case FrictionStatus::ok:
      return "ok";
    case FrictionStatus::non_finite_input:
      return "non-finite current, velocity or estimate";
  }
  return "unknown status";
}

//! Friction constants of one joint, all >= 0 (signs: docs/models/friction_model.md).
template <typename Scalar = double>
struct JointFriction {
  Scalar static_level = 0;   //!< Ks, A: |current| that breaks the joint away from standstill
  Scalar coulomb_level = 0;  //!< Kc, A: current spent on friction while sliding (eq. 5.7)
  Scalar viscous_gain = 0;   //!< F_mu, A s/rad: extra friction current per rad/s (eq. 5.5)

  //! The simplified 2016 model (5.2.2 "Results"): Kc = Ks = level, F_mu = 0.
  [[nodiscard]] static constexpr JointFriction simplified(Scalar level) noexcept {
    return {level, level, Scalar(0)};
  }
  //! Member-wise equality.
  friend bool operator==(const JointFriction&, const JointFriction&) = default;
};

//! Table 5.2 presets (simplified model, Kc = Ks, F_mu = 0), in A. The roll value is doubtful:
//! the 2016 analysis script and the logs give about 0.13 A (docs/models/friction_model.md).
namespace friction_2016 {
//! Roll: 0.7 A (doubtful, see above).
inline constexpr JointFriction<double> roll = JointFriction<double>::simplified(0.7);
//! Pitch: 0.17 A.
inline constexpr JointFriction<double> pitch = JointFriction<double>::simplified(0.17);
//! Yaw: 0.21 A.
inline constexpr JointFriction<double> yaw = JointFriction<double>::simplified(0.21);
//! Clamp: 0.20 A.
inline constexpr JointFriction<double> clamp = JointFriction<double>::simplified(0.20);
//! Joint order of `endowrist_2016_friction` (the row order of table 5.2).
enum Joint : int { roll_joint = 0, pitch_joint = 1, yaw_joint = 2, clamp_joint = 3 };
}  // namespace friction_2016

//! Thresholds of the model and of the 5.2.3 gate.
template <typename Scalar = double>
struct FrictionOptions {
  //! |omega| <= this counts as "omega == 0" of eqs. 5.6/5.7, rad/s. Must exceed the velocity
  //! noise of the source (0.01 rad/s ~ 1.2 encoder ticks per 10 ms sample).
  Scalar standstill_velocity = Scalar(0.01);
  //! An open gate closes when |current| < release_fraction * level; 1 reproduces the 2016 gate
  //! (no hysteresis). 0.75 leaves a band wider than the ~0.035 A peak current noise at 0.2 A.
  Scalar release_fraction = Scalar(0.75);
};

//! Friction model and force-feedback gate for N joints (eqs. 5.4-5.7, section 5.2.3).
//! Per-tick calls are noexcept, allocation-free and write caller-owned outputs.
template <int N, typename Scalar = double>
class FrictionModel {
  static_assert(N >= 1, "FrictionModel needs at least one joint (N >= 1)");
  static_assert(std::is_floating_point_v<Scalar>, "FrictionModel Scalar must be floating point");

 public:
  static constexpr int joints = N;             //!< number of joints
  using Vector = Eigen::Matrix<Scalar, N, 1>;  //!< one value per joint
  using Joint = JointFriction<Scalar>;         //!< friction constants of one joint
  using Joints = std::array<Joint, static_cast<std::size_t>(N)>;  //!< constants of every joint
  using Options = FrictionOptions<Scalar>;  //!< thresholds of the model and gate
  using GateState = std::array<bool, static_cast<std::size_t>(N)>;  //!< per joint: gate open

  //! Throws Error when a constant is negative or not finite, standstill_velocity is negative or
  //! not finite, or release_fraction is outside (0, 1]; the message names joint, field, value.
  explicit FrictionModel(const Joints& joint_constants, const Options& options = {})
      : joints_(joint_constants), options_(options) {
    for (std::size_t j = 0; j < joints_.size(); ++j) {
      check_level(joints_[j].static_level, j, "static_level (Ks)");
      check_level(joints_[j].coulomb_level, j, "coulomb_level (Kc)");
      check_level(joints_[j].viscous_gain, j, "viscous_gain (F_mu)");
    }
    if (!std::isfinite(options_.standstill_velocity) || options_.standstill_velocity < 0) {
      ENDOHAPTICS_THROW(
          Error("FrictionModel: standstill_velocity must be finite and >= 0 rad/s, got " +
                endohaptics::detail::format_number(options_.standstill_velocity)));
    }
    if (!(options_.release_fraction > 0 && options_.release_fraction <= 1)) {
      ENDOHAPTICS_THROW(Error("FrictionModel: release_fraction must lie in (0, 1], got " +
                              endohaptics::detail::format_number(options_.release_fraction)));
    }
  }

  //! Constants of joint `j`. Precondition: 0 <= j < N.
  [[nodiscard]] const Joint& joint(int j) const noexcept {
    ENDOHAPTICS_ASSERT(j >= 0 && j < N);
    return joints_[static_cast<std::size_t>(j)];
  }
  [[nodiscard]] const Options& options() const noexcept { return options_; }  //!< thresholds
  //! Gate state per joint: true while the estimate is fed back.
  [[nodiscard]] const GateState& gate_open() const noexcept { return open_; }
  //! Closes every gate.
  void reset() noexcept { open_.fill(false); }

  //! |current| friction can absorb at `velocity`: Ks at standstill, Kc + F_mu |omega| when
  //! sliding. A non-finite velocity gives level 0 for that joint and `non_finite_input`.
  [[nodiscard]] FrictionStatus breakaway_level(const Vector& velocity,
                                               Vector& level) const noexcept {
    FrictionStatus status = FrictionStatus::ok;
    for (int j = 0; j < N; ++j) {
      if (!std::isfinite(velocity[j])) {
        level[j] = 0;
        status = FrictionStatus::non_finite_input;
        continue;
      }
      level[j] = level_of(j, velocity[j]);
    }
    return status;
  }

  //! Current spent on friction (eq. 5.4, sign of the motion): F_mu omega + Kc sign(omega) when
  //! sliding; at standstill the static friction balances the applied current up to +-Ks.
  //! `external` = current - friction, the part left for external forces. Non-finite inputs give
  //! 0 on both outputs for that joint and `non_finite_input`.
  [[nodiscard]] FrictionStatus compensate(const Vector& current, const Vector& velocity,
                                          Vector& friction, Vector& external) const noexcept {
    FrictionStatus status = FrictionStatus::ok;
    for (int j = 0; j < N; ++j) {
      const Scalar i = current[j];
      const Scalar w = velocity[j];
      if (!std::isfinite(i) || !std::isfinite(w)) {
        friction[j] = 0;
        external[j] = 0;
        status = FrictionStatus::non_finite_input;
        continue;
      }
      const Joint& c = joints_[static_cast<std::size_t>(j)];
      Scalar f;
      if (std::abs(w) <= options_.standstill_velocity) {
        f = std::clamp(i, -c.static_level, c.static_level);
      } else {
        f = c.viscous_gain * w + std::copysign(c.coulomb_level, w);
      }
      friction[j] = f;
      external[j] = i - f;
    }
    return status;
  }

  //! One tick of the 5.2.3 gate: a closed gate opens when |current| > level(velocity), an open
  //! one closes when |current| < release_fraction * level(velocity); `feedback` = estimate where
  //! open, else 0. A joint with a non-finite current, velocity or estimate is closed, its
  //! feedback is 0 and the result is `non_finite_input`; the other joints are unaffected.
  [[nodiscard]] FrictionStatus update(const Vector& current, const Vector& velocity,
                                      const Vector& estimate, Vector& feedback) noexcept {
    FrictionStatus status = FrictionStatus::ok;
    for (int j = 0; j < N; ++j) {
      const auto js = static_cast<std::size_t>(j);
      if (!std::isfinite(current[j]) || !std::isfinite(velocity[j]) ||
          !std::isfinite(estimate[j])) {
        open_[js] = false;
        feedback[j] = 0;
        status = FrictionStatus::non_finite_input;
        continue;
      }
      const Scalar magnitude = std::abs(current[j]);
      const Scalar level = level_of(j, velocity[j]);
      if (open_[js]) {
        open_[js] = !(magnitude < options_.release_fraction * level);
      } else {
        open_[js] = magnitude > level;
      }
      feedback[j] = open_[js] ? estimate[j] : Scalar(0);
    }
    return status;
  }

 private:
  Scalar level_of(int j, Scalar w) const noexcept {
    const Joint& c = joints_[static_cast<std::size_t>(j)];
    const Scalar speed = std::abs(w);
    return speed <= options_.standstill_velocity ? c.static_level
                                                 : c.coulomb_level + c.viscous_gain * speed;
  }

  static void check_level(Scalar value, std::size_t j, std::string_view field) {
    if (!std::isfinite(value) || value < 0) {
      ENDOHAPTICS_THROW(Error("FrictionModel: joint " + std::to_string(j) + " " +
                              std::string(field) + " must be finite and >= 0, got " +
                              endohaptics::detail::format_number(value)));
    }
  }

  Joints joints_;
  Options options_;
  GateState open_{};
};

//! The 2016 simplified model with table 5.2 levels, joints in the order of friction_2016::Joint
//! (roll, pitch, yaw, clamp). Throws Error on invalid `options`.
template <typename Scalar = double>
[[nodiscard]] FrictionModel<4, Scalar> endowrist_2016_friction(
    const FrictionOptions<Scalar>& options = {}) {
  auto cast = [](const JointFriction<double>& j) {
    return JointFriction<Scalar>{static_cast<Scalar>(j.static_level),
                                 static_cast<Scalar>(j.coulomb_level),
                                 static_cast<Scalar>(j.viscous_gain)};
  };
  return FrictionModel<4, Scalar>({cast(friction_2016::roll), cast(friction_2016::pitch),
                                   cast(friction_2016::yaw), cast(friction_2016::clamp)},
                                  options);
}

// ---------------------------------------------------------------------------------------------
// Identification from free-movement logs (configuration time: allocates, throws Error).
// Needs exceptions: left out of -fno-exceptions builds, where only the per-tick model is used.
#if defined(__cpp_exceptions) || defined(__EXCEPTIONS)

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
  JointFriction<double> joint;    //!< Ks (NaN if no onset), Kc, F_mu (sample-weighted over fits)
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
inline std::array<double, 2> huber_line(const std::vector<double>& x, const std::vector<double>& y,
                                        double k) {
  std::vector<double> w(x.size(), 1.0);
  std::vector<double> r(x.size());
  std::array<double, 2> ab{0.0, 0.0};
  for (int iteration = 0; iteration < 50; ++iteration) {
    double sw = 0, sx = 0, sy = 0, sxx = 0, sxy = 0;
    for (std::size_t i = 0; i < x.size(); ++i) {
      sw += w[i];
      sx += w[i] * x[i];
      sy += w[i] * y[i];
      sxx += w[i] * x[i] * x[i];
      sxy += w[i] * x[i] * y[i];
    }
    const double det = sw * sxx - sx * sx;
    const std::array<double, 2> next =
        std::abs(det) > 1e-12 * sw * sxx
            ? std::array<double, 2>{(sxx * sy - sx * sxy) / det, (sw * sxy - sx * sy) / det}
            : std::array<double, 2>{sy / sw, 0.0};  // all x equal: level only
    const bool converged = std::abs(next[0] - ab[0]) < 1e-12 && std::abs(next[1] - ab[1]) < 1e-12;
    ab = next;
    if (converged && iteration > 0) break;
    for (std::size_t i = 0; i < x.size(); ++i) r[i] = y[i] - ab[0] - ab[1] * x[i];
    const double centre = median(r);
    std::vector<double> deviation(r.size());
    for (std::size_t i = 0; i < r.size(); ++i) deviation[i] = std::abs(r[i] - centre);
    const double scale = 1.4826 * median(deviation);
    if (!(scale > 0)) break;
    for (std::size_t i = 0; i < x.size(); ++i) {
      const double u = std::abs(r[i]) / (k * scale);
      w[i] = u <= 1.0 ? 1.0 : 1.0 / u;
    }
  }
  return ab;
}

inline void require_positive(double value, std::string_view name) {
  if (!std::isfinite(value) || !(value > 0)) {
    ENDOHAPTICS_THROW(Error("identify_friction: option " + std::string(name) +
                            " must be finite and > 0, got " +
                            endohaptics::detail::format_number(value)));
  }
}

}  // namespace detail::friction

//! Estimates Ks, Kc, F_mu of one joint from a free-movement log: time [s], encoder ticks,
//! motor current [A], one row per sample. Procedure (docs/models/friction_model.md): drop
//! non-finite rows and non-increasing times; split at gaps > max_gap; resample each segment
//! linearly on a grid_period grid; omega by central difference; Kc and F_mu by a Huber fit of
//! |current| against |omega| over sliding samples, per direction; Ks = the largest |current| at
//! a motion onset after >= min_standstill of standstill. Throws Error when the arrays differ in
//! length, an option is invalid, or no direction has min_fit_samples sliding samples.
[[nodiscard]] inline FrictionIdentification identify_friction(
    std::span<const double> time, std::span<const double> ticks, std::span<const double> current,
    const FrictionIdentificationOptions& options = {}) {
  if (time.size() != ticks.size() || time.size() != current.size()) {
    ENDOHAPTICS_THROW(Error("identify_friction: arrays differ in length (time " +
                            std::to_string(time.size()) + ", ticks " +
                            std::to_string(ticks.size()) + ", current " +
                            std::to_string(current.size()) + ")"));
  }
  detail::friction::require_positive(options.radians_per_tick, "radians_per_tick");
  detail::friction::require_positive(options.grid_period, "grid_period");
  detail::friction::require_positive(options.max_gap, "max_gap");
  detail::friction::require_positive(options.moving_velocity, "moving_velocity");
  detail::friction::require_positive(options.huber_k, "huber_k");
  if (!std::isfinite(options.standstill_velocity) || options.standstill_velocity < 0 ||
      options.standstill_velocity >= options.moving_velocity) {
    ENDOHAPTICS_THROW(
        Error("identify_friction: standstill_velocity must lie in [0, moving_velocity), got " +
              endohaptics::detail::format_number(options.standstill_velocity)));
  }
  if (options.min_fit_samples < 2) {
    ENDOHAPTICS_THROW(Error("identify_friction: min_fit_samples must be >= 2, got " +
                            std::to_string(options.min_fit_samples)));
  }

  FrictionIdentification result;
  result.samples_in = time.size();

  // 1. Clean: finite rows with strictly increasing time.
  std::vector<double> t, theta, amps;
  t.reserve(time.size());
  theta.reserve(time.size());
  amps.reserve(time.size());
  for (std::size_t k = 0; k < time.size(); ++k) {
    if (!std::isfinite(time[k]) || !std::isfinite(ticks[k]) || !std::isfinite(current[k])) {
      ++result.dropped_non_finite;
    } else if (!t.empty() && !(time[k] > t.back())) {
      ++result.dropped_time_order;
    } else {
      t.push_back(time[k]);
      theta.push_back(ticks[k] * options.radians_per_tick);
      amps.push_back(current[k]);
    }
  }

  // 2-4. Segments, resampling, central-difference velocity, onsets.
  const double h = options.grid_period;
  const auto standstill_steps =
      static_cast<std::size_t>(std::ceil(options.min_standstill / h - 1e-9));
  const auto confirm_steps =
      std::max<std::size_t>(1, static_cast<std::size_t>(std::llround(options.onset_confirm / h)));
  const auto window_steps =
      std::max<std::size_t>(1, static_cast<std::size_t>(std::llround(options.onset_window / h)));
  std::vector<double> omega_all, current_all;
  std::vector<std::pair<double, double>> onsets;  // (direction of omega, median current)
  std::size_t begin = 0;
  while (begin < t.size()) {
    std::size_t end = begin + 1;
    while (end < t.size() && t[end] - t[end - 1] <= options.max_gap) ++end;
    if (end < t.size()) ++result.gaps;
    const double span = t[end - 1] - t[begin];
    const auto points = static_cast<std::size_t>(std::floor(span / h + 1e-9)) + 1;
    if (end - begin < 3 || points < 3) {
      result.dropped_short_segments += end - begin;
      begin = end;
      continue;
    }
    std::vector<double> pos(points), amp(points);
    std::size_t src = begin;
    for (std::size_t g = 0; g < points; ++g) {
      const double tg = t[begin] + static_cast<double>(g) * h;
      while (src + 2 < end && t[src + 1] < tg) ++src;
      const double a = std::clamp((tg - t[src]) / (t[src + 1] - t[src]), 0.0, 1.0);
      pos[g] = theta[src] + a * (theta[src + 1] - theta[src]);
      amp[g] = amps[src] + a * (amps[src + 1] - amps[src]);
    }
    std::vector<double> omega(points, 0.0);
    for (std::size_t g = 1; g + 1 < points; ++g) omega[g] = (pos[g + 1] - pos[g - 1]) / (2 * h);

    std::size_t still = 0;
    for (std::size_t g = 1; g + 1 < points; ++g) {
      omega_all.push_back(omega[g]);
      current_all.push_back(amp[g]);
      if (std::abs(omega[g]) <= options.standstill_velocity) {
        ++still;
        continue;
      }
      if (still >= standstill_steps) {
        for (std::size_t c = g; c < std::min(g + confirm_steps, points - 1); ++c) {
          if (std::abs(omega[c]) > options.moving_velocity) {
            const std::size_t first = g - 1;
            const std::size_t last = std::min(g + window_steps, points);
            const double level = detail::friction::median(
                std::vector<double>(amp.begin() + static_cast<std::ptrdiff_t>(first),
                                    amp.begin() + static_cast<std::ptrdiff_t>(last)));
            onsets.emplace_back(omega[c] > 0 ? 1.0 : -1.0, level);
            break;
          }
        }
      }
      still = 0;
    }
    begin = end;
  }
  result.grid_samples = omega_all.size();

  // 5. Which way does positive current push? Majority of sign(omega) * sign(current) in motion.
  long vote = 0;
  for (std::size_t k = 0; k < omega_all.size(); ++k) {
    if (std::abs(omega_all[k]) > options.moving_velocity) {
      ++result.moving_samples;
      vote += (omega_all[k] > 0) == (current_all[k] > 0) ? 1 : -1;
    }
  }
  result.current_sign = vote >= 0 ? 1 : -1;
  const double s = result.current_sign;

  // 6. Per-direction robust affine fit of the friction current against speed.
  for (const double direction : {1.0, -1.0}) {
    std::vector<double> x, y;
    for (std::size_t k = 0; k < omega_all.size(); ++k) {
      if (std::abs(omega_all[k]) > options.moving_velocity && omega_all[k] * direction > 0) {
        x.push_back(std::abs(omega_all[k]));
        y.push_back(s * direction * current_all[k]);
      }
    }
    FrictionDirectionFit& fit = direction > 0 ? result.positive : result.negative;
    fit.samples = x.size();
    if (x.size() >= options.min_fit_samples) {
      const auto ab = detail::friction::huber_line(x, y, options.huber_k);
      fit.coulomb_level = ab[0];
      fit.viscous_gain = ab[1];
    }
  }
  if (!result.positive.valid() && !result.negative.valid()) {
    ENDOHAPTICS_THROW(Error(
        "identify_friction: too little sliding motion (" + std::to_string(result.positive.samples) +
        " samples with omega > +" + endohaptics::detail::format_number(options.moving_velocity) +
        " rad/s, " + std::to_string(result.negative.samples) + " below -, need " +
        std::to_string(options.min_fit_samples) + " in one direction)"));
  }

  // 7. Combine: sample-weighted over valid directions; Ks = largest onset current.
  double weight = 0, kc = 0, fmu = 0;
  for (const FrictionDirectionFit* fit : {&result.positive, &result.negative}) {
    if (!fit->valid()) continue;
    const auto n = static_cast<double>(fit->samples);
    weight += n;
    kc += n * fit->coulomb_level;
    fmu += n * fit->viscous_gain;
  }
  result.joint.coulomb_level = kc / weight;
  result.joint.viscous_gain = fmu / weight;
  result.joint.static_level = std::numeric_limits<double>::quiet_NaN();
  for (const auto& [direction, level] : onsets) {
    const double magnitude = s * direction * level;
    result.onset_currents.push_back(magnitude);
    if (!(result.joint.static_level >= magnitude)) result.joint.static_level = magnitude;
  }
  return result;
}

#endif  // exceptions enabled

}  // namespace endohaptics::model
