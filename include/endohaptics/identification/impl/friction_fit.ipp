//! @file
//! Function bodies of identification/friction_fit.hpp: included at its end (header-only, the
//! default), or compiled once with ENDOHAPTICS_SEPARATE_COMPILATION
//! (core/separate_compilation.hpp).
#pragma once

#include "endohaptics/identification/friction_fit.hpp"

namespace endohaptics::identification {
namespace detail::friction {

ENDOHAPTICS_DECL std::array<double, 2> huber_line(const std::vector<double>& x,
                                                  const std::vector<double>& y, double k) {
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

ENDOHAPTICS_DECL void require_positive(double value, std::string_view name) {
  if (!std::isfinite(value) || !(value > 0)) {
    ENDOHAPTICS_THROW(Error("identify_friction: option " + std::string(name) +
                            " must be finite and > 0, got " +
                            endohaptics::detail::format_number(value)));
  }
}
}  // namespace detail::friction
}  // namespace endohaptics::identification

namespace endohaptics::identification {

ENDOHAPTICS_DECL FrictionIdentification
identify_friction(std::span<const double> time, std::span<const double> ticks,
                  std::span<const double> current, const FrictionIdentificationOptions& options) {
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

  // 1. Clean: finite rows with strictly increasing time; `signals` columns: position rad, current
  // A.
  Eigen::VectorXd t(static_cast<Eigen::Index>(time.size()));
  Eigen::MatrixXd signals(t.size(), 2);
  Eigen::Index kept = 0;
  for (std::size_t k = 0; k < time.size(); ++k) {
    if (!std::isfinite(time[k]) || !std::isfinite(ticks[k]) || !std::isfinite(current[k])) {
      ++result.dropped_non_finite;
    } else if (kept > 0 && !(time[k] > t[kept - 1])) {
      ++result.dropped_time_order;
    } else {
      t[kept] = time[k];
      signals(kept, 0) = ticks[k] * options.radians_per_tick;
      signals(kept, 1) = current[k];
      ++kept;
    }
  }

  // 2-3. Segments split at gaps > max_gap, linear resampling on the grid (resample_uniform), and
  // the central difference (central_difference). Segments of fewer than 3 source rows or 3 grid
  // points cannot be differentiated and are dropped. Only interior grid points are used, where
  // central_difference is (pos[g + 1] - pos[g - 1]) / 2h; its one-sided end values are not.
  const double h = options.grid_period;
  const Segments segments =
      resample_uniform(t.head(kept), signals.topRows(kept), h, ResampleOptions{options.max_gap, 3});
  result.gaps = segments.gaps;
  result.dropped_short_segments = segments.dropped_source_rows;

  // 4. Velocity, onsets.
  const auto standstill_steps =
      static_cast<std::size_t>(std::ceil(options.min_standstill / h - 1e-9));
  const auto confirm_steps =
      std::max<Eigen::Index>(1, static_cast<Eigen::Index>(std::llround(options.onset_confirm / h)));
  const auto window_steps =
      std::max<Eigen::Index>(1, static_cast<Eigen::Index>(std::llround(options.onset_window / h)));
  std::vector<double> omega_all, current_all;
  std::vector<std::pair<double, double>> onsets;  // (direction of omega, median current)
  for (const UniformSegment& segment : segments.segments) {
    const Eigen::Index source_rows = segment.last_source - segment.first_source + 1;
    if (source_rows < 3) {
      result.dropped_short_segments += static_cast<std::size_t>(source_rows);
      continue;
    }
    const Eigen::Index points = segment.rows();
    const Eigen::VectorXd omega = central_difference(segment.data.col(0), h);
    const Eigen::VectorXd amp = segment.data.col(1);

    std::size_t still = 0;
    for (Eigen::Index g = 1; g + 1 < points; ++g) {
      omega_all.push_back(omega[g]);
      current_all.push_back(amp[g]);
      if (std::abs(omega[g]) <= options.standstill_velocity) {
        ++still;
        continue;
      }
      if (still >= standstill_steps) {
        for (Eigen::Index c = g; c < std::min(g + confirm_steps, points - 1); ++c) {
          if (std::abs(omega[c]) > options.moving_velocity) {
            const Eigen::Index first = g - 1;
            const Eigen::Index last = std::min(g + window_steps, points);
            const double level = detail::friction::median(
                std::vector<double>(amp.data() + first, amp.data() + last));
            onsets.emplace_back(omega[c] > 0 ? 1.0 : -1.0, level);
            break;
          }
        }
      }
      still = 0;
    }
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

}  // namespace endohaptics::identification
