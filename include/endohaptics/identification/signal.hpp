//! @file
//! Signal conditioning before system identification (worksheet 4.2.1: low-pass filtering,
//! offset removal): uniform resampling split at time gaps, differentiators, Butterworth low-pass
//! design (bilinear with prewarping, second-order sections, as scipy.signal.butter) and
//! zero-phase filtering (as scipy.signal.sosfiltfilt), offset removal and detrending.
//! Times in s, frequencies in Hz. Configuration time: allocates, throws endohaptics::Error.
#pragma once

#include <Eigen/Core>
#include <Eigen/QR>
#include <algorithm>
#include <cmath>
#include <complex>
#include <cstddef>
#include <cstdint>
#include <limits>
#include <numbers>
#include <sstream>
#include <string>
#include <string_view>
#include <vector>

#include "endohaptics/core/error.hpp"
#include "endohaptics/core/median.hpp"

namespace endohaptics::identification {

namespace detail::signal {

//! Round-trip formatting of a number for error messages.
inline std::string format(double value) {
  std::ostringstream out;
  out.precision(std::numeric_limits<double>::max_digits10);
  out << value;
  return out.str();
}

[[noreturn]] inline void fail(std::string_view function, const std::string& what) {
  ENDOHAPTICS_THROW(Error(std::string(function) + ": " + what));
}

inline void require_positive(double value, std::string_view function, std::string_view name) {
  if (!std::isfinite(value) || !(value > 0)) {
    fail(function, std::string(name) + " must be finite and > 0, got " + format(value));
  }
}

using endohaptics::detail::median;

//! Throws unless `time` is finite and strictly increasing.
inline void require_increasing(const Eigen::Ref<const Eigen::VectorXd>& time,
                               std::string_view function) {
  for (Eigen::Index k = 0; k < time.size(); ++k) {
    if (!std::isfinite(time[k])) {
      fail(function, "time[" + std::to_string(k) + "] is not finite (" + format(time[k]) + ")");
    }
    if (k > 0 && !(time[k] > time[k - 1])) {
      fail(function, "time must increase strictly, but time[" + std::to_string(k) +
                         "] = " + format(time[k]) + " after " + format(time[k - 1]));
    }
  }
}

}  // namespace detail::signal

// ---------------------------------------------------------------------------------------------
// Time steps and resampling

//! Median of the time steps (s); NaN for fewer than two samples.
[[nodiscard]] inline double median_step(const Eigen::Ref<const Eigen::VectorXd>& time) {
  std::vector<double> steps;
  steps.reserve(static_cast<std::size_t>(std::max<Eigen::Index>(time.size() - 1, 0)));
  for (Eigen::Index k = 1; k < time.size(); ++k) steps.push_back(time[k] - time[k - 1]);
  return detail::signal::median(std::move(steps));
}

//! One stretch of data without gaps on a uniform grid: row k is at start_time + k * sample_time.
struct UniformSegment {
  double start_time = 0;          //!< s, time of row 0 (the first source sample of the stretch)
  double sample_time = 0;         //!< s
  Eigen::MatrixXd data;           //!< rows: samples, columns: signals in the caller's order
  Eigen::Index first_source = 0;  //!< first source row covered
  Eigen::Index last_source = 0;   //!< last source row covered (inclusive)

  //! Number of grid samples (rows of `data`).
  [[nodiscard]] Eigen::Index rows() const noexcept { return data.rows(); }
  //! The grid times, s.
  [[nodiscard]] Eigen::VectorXd time() const {
    return Eigen::VectorXd::LinSpaced(data.rows(), 0.0, static_cast<double>(data.rows() - 1)) *
               sample_time +
           Eigen::VectorXd::Constant(data.rows(), start_time);
  }
};

//! Settings of `resample_uniform`.
struct ResampleOptions {
  //! Source time steps longer than this split the data (s); 0: 5 x max(ts, median source step).
  double max_gap = 0;
  //! Stretches that give fewer grid samples are dropped (and counted).
  Eigen::Index min_samples = 2;
  //! Largest number of grid samples of one stretch (a tiny ts on a long log): more throws Error
  //! before anything is allocated. 10^8 samples are 800 MB per signal.
  Eigen::Index max_samples = 100'000'000;
};

//! Uniformly sampled stretches, with the bookkeeping of what was split or dropped.
struct Segments {
  std::vector<UniformSegment> segments;  //!< in time order
  double max_gap = 0;                    //!< the gap threshold used, s
  std::size_t gaps = 0;                  //!< source steps > max_gap (split points)
  double largest_step = 0;               //!< largest source time step, s
  std::size_t dropped_segments = 0;      //!< stretches shorter than min_samples
  std::size_t dropped_source_rows = 0;   //!< source rows in those stretches
  //! Filled by `preprocess`: offset removed from each column (0 where none), same units.
  Eigen::VectorXd offsets;

  //! Total grid samples over all segments.
  [[nodiscard]] Eigen::Index samples() const noexcept {
    Eigen::Index n = 0;
    for (const auto& s : segments) n += s.rows();
    return n;
  }
  //! The segment with the most samples. Throws Error when there is none.
  [[nodiscard]] const UniformSegment& longest() const {
    if (segments.empty()) detail::signal::fail("Segments::longest", "no segment");
    return *std::max_element(segments.begin(), segments.end(),
                             [](const auto& a, const auto& b) { return a.rows() < b.rows(); });
  }
};

//! Linear interpolation of `signals` (rows = samples, one column per signal) onto the grid
//! start + k * ts of each stretch between time steps > max_gap: no data is invented across a
//! gap. A stretch starts at its first source sample; its last grid point is at or before its
//! last source sample. Throws Error when sizes differ, ts <= 0, time is not finite and strictly
//! increasing, a signal value is not finite (naming row and column), or a stretch would give
//! more than options.max_samples grid samples.
[[nodiscard]] inline Segments resample_uniform(const Eigen::Ref<const Eigen::VectorXd>& time,
                                               const Eigen::Ref<const Eigen::MatrixXd>& signals,
                                               double ts, const ResampleOptions& options = {}) {
  constexpr std::string_view fn = "resample_uniform";
  detail::signal::require_positive(ts, fn, "sample time ts");
  if (signals.rows() != time.size()) {
    detail::signal::fail(fn, "time has " + std::to_string(time.size()) + " samples but signals " +
                                 std::to_string(signals.rows()) + " rows");
  }
  if (!std::isfinite(options.max_gap) || options.max_gap < 0) {
    detail::signal::fail(
        fn, "max_gap must be finite and >= 0, got " + detail::signal::format(options.max_gap));
  }
  detail::signal::require_increasing(time, fn);
  for (Eigen::Index c = 0; c < signals.cols(); ++c) {
    for (Eigen::Index r = 0; r < signals.rows(); ++r) {
      if (!std::isfinite(signals(r, c))) {
        detail::signal::fail(fn, "signal value at row " + std::to_string(r) + ", column " +
                                     std::to_string(c) + " is not finite");
      }
    }
  }

  Segments out;
  const double source_step = median_step(time);
  out.max_gap = options.max_gap > 0
                    ? options.max_gap
                    : 5.0 * (std::isfinite(source_step) ? std::max(ts, source_step) : ts);
  const Eigen::Index n = time.size();
  Eigen::Index begin = 0;
  while (begin < n) {
    Eigen::Index end = begin + 1;  // exclusive
    while (end < n && time[end] - time[end - 1] <= out.max_gap) {
      out.largest_step = std::max(out.largest_step, time[end] - time[end - 1]);
      ++end;
    }
    if (end < n) {
      ++out.gaps;
      out.largest_step = std::max(out.largest_step, time[end] - time[end - 1]);
    }
    const double span = time[end - 1] - time[begin];
    const double grid = std::floor(span / ts + 1e-9) + 1.0;
    if (!(grid <= static_cast<double>(options.max_samples))) {
      detail::signal::fail(fn, "a stretch of " + detail::signal::format(span) +
                                   " s at ts = " + detail::signal::format(ts) + " s gives " +
                                   detail::signal::format(grid) + " grid samples, more than " +
                                   "the limit of " + std::to_string(options.max_samples));
    }
    const auto points = static_cast<Eigen::Index>(grid);
    if (points < std::max<Eigen::Index>(options.min_samples, 1)) {
      ++out.dropped_segments;
      out.dropped_source_rows += static_cast<std::size_t>(end - begin);
      begin = end;
      continue;
    }
    UniformSegment segment;
    segment.start_time = time[begin];
    segment.sample_time = ts;
    segment.first_source = begin;
    segment.last_source = end - 1;
    segment.data.resize(points, signals.cols());
    Eigen::Index src = begin;
    for (Eigen::Index g = 0; g < points; ++g) {
      const double tg = time[begin] + static_cast<double>(g) * ts;
      while (src + 1 < end - 1 && time[src + 1] <= tg) ++src;
      if (src + 1 >= end) {  // single-sample stretch
        segment.data.row(g) = signals.row(src);
        continue;
      }
      const double a = std::clamp((tg - time[src]) / (time[src + 1] - time[src]), 0.0, 1.0);
      segment.data.row(g) = (1.0 - a) * signals.row(src) + a * signals.row(src + 1);
    }
    out.segments.push_back(std::move(segment));
    begin = end;
  }
  return out;
}

// ---------------------------------------------------------------------------------------------
// Differentiators

//! Derivative on the source time stamps: the secant over the two neighbours,
//! (x[k+1] - x[k-1]) / (t[k+1] - t[k-1]), one-sided at both ends and next to steps > max_gap;
//! 0 for a sample isolated between two gaps. On a uniform grid this is the central difference.
//! Throws Error when sizes differ or time is not finite and strictly increasing.
[[nodiscard]] inline Eigen::VectorXd differentiate(const Eigen::Ref<const Eigen::VectorXd>& time,
                                                   const Eigen::Ref<const Eigen::VectorXd>& x,
                                                   double max_gap) {
  constexpr std::string_view fn = "differentiate";
  if (time.size() != x.size()) {
    detail::signal::fail(fn, "time has " + std::to_string(time.size()) + " samples but x " +
                                 std::to_string(x.size()));
  }
  detail::signal::require_positive(max_gap, fn, "max_gap");
  detail::signal::require_increasing(time, fn);
  const Eigen::Index n = x.size();
  Eigen::VectorXd v = Eigen::VectorXd::Zero(n);
  for (Eigen::Index k = 0; k < n; ++k) {
    const bool has_prev = k > 0 && time[k] - time[k - 1] <= max_gap;
    const bool has_next = k + 1 < n && time[k + 1] - time[k] <= max_gap;
    const Eigen::Index lo = has_prev ? k - 1 : k;
    const Eigen::Index hi = has_next ? k + 1 : k;
    if (hi > lo) v[k] = (x[hi] - x[lo]) / (time[hi] - time[lo]);
  }
  return v;
}

//! Central difference on a uniform grid, (x[k+1] - x[k-1]) / (2 ts), one-sided first
//! differences at the ends (numpy.gradient(x, ts) with edge_order=1). Precondition: ts > 0.
//! Throws Error for ts <= 0 or fewer than 2 samples.
[[nodiscard]] inline Eigen::VectorXd central_difference(const Eigen::Ref<const Eigen::VectorXd>& x,
                                                        double ts) {
  detail::signal::require_positive(ts, "central_difference", "sample time ts");
  const Eigen::Index n = x.size();
  if (n < 2)
    detail::signal::fail("central_difference", "needs >= 2 samples, got " + std::to_string(n));
  Eigen::VectorXd v(n);
  v[0] = (x[1] - x[0]) / ts;
  v[n - 1] = (x[n - 1] - x[n - 2]) / ts;
  for (Eigen::Index k = 1; k + 1 < n; ++k) v[k] = (x[k + 1] - x[k - 1]) / (2.0 * ts);
  return v;
}

//! Savitzky-Golay filter: at each sample the `deriv`-th derivative of the least-squares
//! polynomial of degree `polyorder` over `window` samples centred on it; the first and last
//! window/2 samples use the polynomial of the first/last full window (scipy.signal.savgol_filter
//! with mode='interp'). Divided by ts^deriv. Throws Error unless window is odd and <= x.size(),
//! 0 <= polyorder < window, 0 <= deriv, ts > 0.
[[nodiscard]] inline Eigen::VectorXd savgol_filter(const Eigen::Ref<const Eigen::VectorXd>& x,
                                                   int window, int polyorder, int deriv = 0,
                                                   double ts = 1.0) {
  constexpr std::string_view fn = "savgol_filter";
  detail::signal::require_positive(ts, fn, "sample time ts");
  if (window < 1 || window % 2 == 0) {
    detail::signal::fail(fn, "window must be odd and >= 1, got " + std::to_string(window));
  }
  if (polyorder < 0 || polyorder >= window) {
    detail::signal::fail(fn, "polyorder must lie in [0, window), got " + std::to_string(polyorder) +
                                 " for window " + std::to_string(window));
  }
  if (deriv < 0) detail::signal::fail(fn, "deriv must be >= 0, got " + std::to_string(deriv));
  if (x.size() < window) {
    detail::signal::fail(fn, "needs at least window = " + std::to_string(window) +
                                 " samples, got " + std::to_string(x.size()));
  }
  const int half = window / 2;
  // Vandermonde in the scaled, centred coordinate u = (j - half) / s (s keeps it well scaled).
  const double s = std::max(1.0, static_cast<double>(half));
  Eigen::MatrixXd vander(window, polyorder + 1);
  for (int j = 0; j < window; ++j) {
    for (int m = 0; m <= polyorder; ++m) vander(j, m) = std::pow((j - half) / s, m);
  }
  const Eigen::MatrixXd fit = vander.completeOrthogonalDecomposition().pseudoInverse();
  // weights(j, :) gives the derivative at window position j from the window's samples.
  Eigen::MatrixXd derivative_row = Eigen::MatrixXd::Zero(window, polyorder + 1);
  for (int j = 0; j < window; ++j) {
    const double u = (j - half) / s;
    for (int m = deriv; m <= polyorder; ++m) {
      double falling = 1.0;  // m! / (m - deriv)!
      for (int i = 0; i < deriv; ++i) falling *= m - i;
      derivative_row(j, m) = falling * std::pow(u, m - deriv) / std::pow(s, deriv);
    }
  }
  const Eigen::MatrixXd weights = derivative_row * fit / std::pow(ts, deriv);
  const Eigen::Index n = x.size();
  const Eigen::Index w = window;
  Eigen::VectorXd y(n);
  for (Eigen::Index k = 0; k < n; ++k) {
    Eigen::Index start = k - half;
    Eigen::Index row = half;
    if (start < 0) {
      start = 0;
      row = k;
    } else if (start + w > n) {
      start = n - w;
      row = k - start;
    }
    y[k] = weights.row(row).dot(x.segment(start, w));
  }
  return y;
}

// ---------------------------------------------------------------------------------------------
// Butterworth low-pass and zero-phase filtering

//! Second-order sections, one per row: b0 b1 b2 a0 a1 a2 with a0 = 1 (scipy's `sos` layout).
using SosMatrix = Eigen::Matrix<double, Eigen::Dynamic, 6>;

//! Digital Butterworth low-pass of `order` (1..32), -3 dB at `cutoff` Hz, for sample time ts:
//! analog prototype, frequency prewarped to 2 fs tan(pi fc / fs), bilinear transform, poles
//! paired with zeros and ordered as scipy.signal.zpk2sos (pairing 'nearest'; the sections
//! whose poles are closest to the unit circle last; gain in the first section). Equals
//! scipy.signal.butter(order, cutoff, fs=1/ts, output='sos'). Throws Error for an order outside
//! 1..32, ts <= 0 or a cutoff outside (0, 1/(2 ts)).
[[nodiscard]] inline SosMatrix butterworth_lowpass(int order, double cutoff, double ts) {
  using Complex = std::complex<double>;
  constexpr std::string_view fn = "butterworth_lowpass";
  constexpr double pi = std::numbers::pi;
  if (order < 1 || order > 32) {
    detail::signal::fail(fn, "order must lie in 1..32, got " + std::to_string(order));
  }
  detail::signal::require_positive(ts, fn, "sample time ts");
  const double nyquist = 0.5 / ts;
  if (!std::isfinite(cutoff) || !(cutoff > 0) || !(cutoff < nyquist)) {
    detail::signal::fail(fn, "cutoff must lie in (0, " + detail::signal::format(nyquist) +
                                 ") Hz (Nyquist for ts = " + detail::signal::format(ts) +
                                 " s), got " + detail::signal::format(cutoff));
  }
  // scipy.signal.iirfilter: normalised Wn = fc / (fs/2); design at fs' = 2, prewarped
  // 2 fs' tan(pi Wn / fs'); bilinear with 2 fs' = 4.
  const double wn = cutoff / nyquist;
  const double warped = 4.0 * std::tan(pi * wn / 2.0);
  std::vector<Complex> analog;  // buttap poles, in scipy's order
  for (int m = -order + 1; m < order; m += 2) {
    analog.push_back(-std::exp(Complex(0.0, pi * m / (2.0 * order))) * warped);
  }
  Complex denominator(1.0, 0.0);
  for (const Complex& p : analog) denominator *= Complex(4.0, 0.0) - p;
  const double gain = std::pow(warped, order) * (Complex(1.0, 0.0) / denominator).real();

  // Digital poles as scipy's _cplxreal leaves them: one of each conjugate pair (imag > 0) sorted
  // by real part, then the real ones ascending; zeros: `order` at -1 (all real). An odd count
  // gets one pole and one zero at the origin (zpk2sos, pairing 'nearest').
  std::vector<Complex> complex_poles;
  std::vector<double> real_poles;
  for (const Complex& p : analog) {
    const Complex pz = (Complex(4.0, 0.0) + p) / (Complex(4.0, 0.0) - p);
    if (std::abs(pz.imag()) <= 100.0 * std::numeric_limits<double>::epsilon() * std::abs(pz)) {
      real_poles.push_back(pz.real());
    } else if (pz.imag() > 0) {
      complex_poles.push_back(pz);
    }
  }
  std::vector<double> zeros(static_cast<std::size_t>(order), -1.0);
  if (order % 2 == 1) {
    real_poles.push_back(0.0);
    zeros.push_back(0.0);
  }
  std::sort(complex_poles.begin(), complex_poles.end(),
            [](const Complex& a, const Complex& b) { return a.real() < b.real(); });
  std::sort(real_poles.begin(), real_poles.end());
  std::sort(zeros.begin(), zeros.end());
  std::vector<Complex> poles(complex_poles.begin(), complex_poles.end());
  for (const double p : real_poles) poles.emplace_back(p, 0.0);

  const auto is_real = [](const Complex& p) { return p.imag() == 0.0; };
  const auto worst = [](const std::vector<Complex>& ps, auto&& keep) {
    std::size_t best = ps.size();
    double distance = std::numeric_limits<double>::infinity();
    for (std::size_t i = 0; i < ps.size(); ++i) {
      if (!keep(ps[i])) continue;
      const double d = std::abs(1.0 - std::abs(ps[i]));
      if (d < distance) {
        distance = d;
        best = i;
      }
    }
    return best;
  };
  const auto take_nearest_zero = [&zeros](const Complex& to) {
    std::size_t best = 0;
    for (std::size_t i = 1; i < zeros.size(); ++i) {
      if (std::abs(zeros[i] - to) < std::abs(zeros[best] - to)) best = i;
    }
    const double z = zeros[best];
    zeros.erase(zeros.begin() + static_cast<std::ptrdiff_t>(best));
    return z;
  };

  const int sections = (static_cast<int>(zeros.size()) + 1) / 2;
  SosMatrix sos = SosMatrix::Zero(sections, 6);
  for (int si = sections - 1; si >= 0; --si) {
    const std::size_t i1 = worst(poles, [](const Complex&) { return true; });
    const Complex p1 = poles[i1];
    poles.erase(poles.begin() + static_cast<std::ptrdiff_t>(i1));
    const bool reals_left = std::any_of(poles.begin(), poles.end(), is_real);
    Complex p2;
    double z1 = 0.0;
    double z2 = 0.0;
    if (is_real(p1) && !reals_left) {  // zpk2sos special case (1): last real pole
      z1 = take_nearest_zero(p1);
      p2 = Complex(0.0, 0.0);
      z2 = 0.0;
    } else {
      if (is_real(p1)) {
        const std::size_t i2 = worst(poles, is_real);
        p2 = poles[i2];
        poles.erase(poles.begin() + static_cast<std::ptrdiff_t>(i2));
      } else {
        p2 = std::conj(p1);
      }
      z1 = take_nearest_zero(p1);
      z2 = take_nearest_zero(p1);
    }
    sos.row(si) << 1.0, -(z1 + z2), z1 * z2, 1.0, -(p1 + p2).real(), (p1 * p2).real();
  }
  sos.row(0).head<3>() *= gain;
  return sos;
}

//! Initial state of each section for a unit step in steady state (scipy.signal.sosfilt_zi),
//! one row per section, transposed direct form II.
[[nodiscard]] inline Eigen::Matrix<double, Eigen::Dynamic, 2> sosfilt_zi(const SosMatrix& sos) {
  Eigen::Matrix<double, Eigen::Dynamic, 2> zi(sos.rows(), 2);
  double scale = 1.0;
  for (Eigen::Index s = 0; s < sos.rows(); ++s) {
    const double b0 = sos(s, 0) / sos(s, 3), b1 = sos(s, 1) / sos(s, 3), b2 = sos(s, 2) / sos(s, 3);
    const double a1 = sos(s, 4) / sos(s, 3), a2 = sos(s, 5) / sos(s, 3);
    const double z0 = ((b1 - a1 * b0) + (b2 - a2 * b0)) / (1.0 + a1 + a2);
    zi(s, 0) = scale * z0;
    zi(s, 1) = scale * ((1.0 + a1) * z0 - (b1 - a1 * b0));
    scale *= (b0 + b1 + b2) / (1.0 + a1 + a2);
  }
  return zi;
}

//! Runs the cascade over `x` (transposed direct form II, scipy.signal.sosfilt) from state `zi`
//! (one row per section; updated to the final state). Throws Error unless every section is
//! finite with a0 = 1 and zi has one row per section.
[[nodiscard]] inline Eigen::VectorXd sosfilt(const SosMatrix& sos,
                                             const Eigen::Ref<const Eigen::VectorXd>& x,
                                             Eigen::Matrix<double, Eigen::Dynamic, 2>& zi) {
  for (Eigen::Index s = 0; s < sos.rows(); ++s) {
    if (sos(s, 3) != 1.0 || !sos.row(s).allFinite()) {
      detail::signal::fail("sosfilt", "section " + std::to_string(s) +
                                          " must be finite with a0 = 1, got a0 = " +
                                          detail::signal::format(sos(s, 3)));
    }
  }
  if (zi.rows() != sos.rows()) {
    detail::signal::fail("sosfilt", "zi has " + std::to_string(zi.rows()) + " rows for " +
                                        std::to_string(sos.rows()) + " sections");
  }
  Eigen::VectorXd y(x.size());
  for (Eigen::Index i = 0; i < x.size(); ++i) {
    double v = x[i];
    for (Eigen::Index s = 0; s < sos.rows(); ++s) {
      const double out = sos(s, 0) * v + zi(s, 0);
      zi(s, 0) = sos(s, 1) * v - sos(s, 4) * out + zi(s, 1);
      zi(s, 1) = sos(s, 2) * v - sos(s, 5) * out;
      v = out;
    }
    y[i] = v;
  }
  return y;
}

//! Padding `filtfilt` adds at each end: 3 (2 sections + 1 - sections with b2 = a2 = 0),
//! scipy.signal.sosfiltfilt's default.
[[nodiscard]] inline Eigen::Index filtfilt_padlen(const SosMatrix& sos) {
  const auto b2_zero = (sos.col(2).array() == 0.0).count();
  const auto a2_zero = (sos.col(5).array() == 0.0).count();
  return 3 * (2 * sos.rows() + 1 - std::min(b2_zero, a2_zero));
}

//! Zero-phase filtering (scipy.signal.sosfiltfilt, padtype 'odd'): odd extension by
//! `filtfilt_padlen` samples at each end, forward pass from the steady state of the first
//! sample, backward pass from the steady state of the last output, extension removed.
//! Magnitude response |H|^2, no delay. Throws Error unless x.size() > filtfilt_padlen(sos).
[[nodiscard]] inline Eigen::VectorXd filtfilt(const SosMatrix& sos,
                                              const Eigen::Ref<const Eigen::VectorXd>& x) {
  const Eigen::Index pad = filtfilt_padlen(sos);
  const Eigen::Index n = x.size();
  if (n <= pad) {
    detail::signal::fail("filtfilt", "needs more than " + std::to_string(pad) +
                                         " samples (the padding), got " + std::to_string(n));
  }
  Eigen::VectorXd ext(n + 2 * pad);
  for (Eigen::Index i = 0; i < pad; ++i) {
    ext[i] = 2.0 * x[0] - x[pad - i];
    ext[pad + n + i] = 2.0 * x[n - 1] - x[n - 2 - i];
  }
  ext.segment(pad, n) = x;
  const Eigen::Matrix<double, Eigen::Dynamic, 2> zi = sosfilt_zi(sos);
  Eigen::Matrix<double, Eigen::Dynamic, 2> state = zi * ext[0];
  Eigen::VectorXd forward = sosfilt(sos, ext, state);
  state = zi * forward[forward.size() - 1];
  const Eigen::VectorXd reversed = forward.reverse();
  const Eigen::VectorXd backward = sosfilt(sos, reversed, state);
  return backward.reverse().segment(pad, n);
}

//! `filtfilt` applied to every column.
[[nodiscard]] inline Eigen::MatrixXd filtfilt_columns(const SosMatrix& sos,
                                                      const Eigen::Ref<const Eigen::MatrixXd>& x) {
  Eigen::MatrixXd y(x.rows(), x.cols());
  for (Eigen::Index c = 0; c < x.cols(); ++c) y.col(c) = filtfilt(sos, x.col(c));
  return y;
}

// ---------------------------------------------------------------------------------------------
// Offsets and trends

//! How an offset is estimated from a window of samples.
enum class OffsetEstimator : std::uint8_t {
  mean,    //!< arithmetic mean
  median,  //!< median (robust to a few contact samples or spikes in the window)
};

//! Samples [first, first + length) of a signal; length < 0 means "to the end".
struct OffsetWindow {
  Eigen::Index first = 0;    //!< first sample of the window
  Eigen::Index length = -1;  //!< number of samples; < 0: all from `first`
  OffsetEstimator estimator = OffsetEstimator::median;  //!< mean or median
};

//! The offset of `x` over `window` (same unit as x). Throws Error when the window is empty or
//! leaves the signal.
[[nodiscard]] inline double estimate_offset(const Eigen::Ref<const Eigen::VectorXd>& x,
                                            const OffsetWindow& window = {}) {
  const Eigen::Index length = window.length < 0 ? x.size() - window.first : window.length;
  if (window.first < 0 || length <= 0 || window.first + length > x.size()) {
    detail::signal::fail("estimate_offset", "window [" + std::to_string(window.first) + ", " +
                                                std::to_string(window.first + length) +
                                                ") is empty or outside the " +
                                                std::to_string(x.size()) + " samples");
  }
  const auto part = x.segment(window.first, length);
  if (window.estimator == OffsetEstimator::mean) return part.mean();
  return detail::signal::median(std::vector<double>(part.begin(), part.end()));
}

//! Subtracts the offset of `window` from all of `x` and returns it.
inline double remove_offset(Eigen::Ref<Eigen::VectorXd> x, const OffsetWindow& window = {}) {
  const double offset = estimate_offset(x, window);
  x.array() -= offset;
  return offset;
}

//! What `detrend` removes.
enum class DetrendType : std::uint8_t {
  constant,  //!< the mean
  linear,    //!< the least-squares straight line over the sample index
};

//! x minus its mean or least-squares line (scipy.signal.detrend). Throws Error for an empty x.
[[nodiscard]] inline Eigen::VectorXd detrend(const Eigen::Ref<const Eigen::VectorXd>& x,
                                             DetrendType type = DetrendType::linear) {
  const Eigen::Index n = x.size();
  if (n == 0) detail::signal::fail("detrend", "empty signal");
  if (type == DetrendType::constant || n == 1) {
    return (x.array() - x.mean()).matrix();
  }
  // Centred index keeps the normal equations well conditioned: slope = sum(k' x) / sum(k'^2).
  const double centre = 0.5 * static_cast<double>(n - 1);
  const Eigen::VectorXd k =
      Eigen::VectorXd::LinSpaced(n, 0.0, static_cast<double>(n - 1)).array() - centre;
  const double slope = k.dot(x) / k.squaredNorm();
  return (x.array() - x.mean() - slope * k.array()).matrix();
}

// ---------------------------------------------------------------------------------------------
// The worksheet 4.2.1 chain in one call

//! Settings of `preprocess`.
struct PreprocessOptions {
  double sample_time = 0;  //!< s, the uniform grid (required, > 0)
  double max_gap = 0;      //!< s; 0: 5 x max(sample_time, median source step)
  double cutoff = 0;       //!< Hz, zero-phase Butterworth low-pass; 0: none (4.2.1: 20 Hz)
  int filter_order = 4;    //!< Butterworth order (filtfilt doubles the attenuation)
  //! Columns whose offset is removed (4.2.1 removes it from the outputs).
  std::vector<Eigen::Index> offset_columns;
  double offset_duration = 0.5;  //!< s at the start of the first segment used for the offset
  OffsetEstimator offset_estimator = OffsetEstimator::median;  //!< mean or median
};

//! Resample onto the uniform grid (split at gaps), low-pass each segment with `filtfilt`
//! (segments too short for its padding are dropped and counted), then subtract from each
//! offset column one offset estimated over the first `offset_duration` of the first segment
//! (after filtering). Throws Error on invalid options or when no segment is left.
[[nodiscard]] inline Segments preprocess(const Eigen::Ref<const Eigen::VectorXd>& time,
                                         const Eigen::Ref<const Eigen::MatrixXd>& signals,
                                         const PreprocessOptions& options) {
  constexpr std::string_view fn = "preprocess";
  detail::signal::require_positive(options.sample_time, fn, "sample_time");
  SosMatrix sos;
  Eigen::Index min_samples = 2;
  if (options.cutoff != 0) {
    sos = butterworth_lowpass(options.filter_order, options.cutoff, options.sample_time);
    min_samples = filtfilt_padlen(sos) + 1;
  }
  for (const Eigen::Index c : options.offset_columns) {
    if (c < 0 || c >= signals.cols()) {
      detail::signal::fail(fn, "offset column " + std::to_string(c) + " outside the " +
                                   std::to_string(signals.cols()) + " signals");
    }
  }
  Segments out = resample_uniform(time, signals, options.sample_time,
                                  ResampleOptions{options.max_gap, min_samples});
  if (out.segments.empty()) {
    detail::signal::fail(fn, "no stretch of data without gaps has " + std::to_string(min_samples) +
                                 " samples at ts = " + detail::signal::format(options.sample_time) +
                                 " s");
  }
  if (sos.rows() > 0) {
    for (auto& segment : out.segments) segment.data = filtfilt_columns(sos, segment.data);
  }
  out.offsets = Eigen::VectorXd::Zero(signals.cols());
  if (!options.offset_columns.empty()) {
    detail::signal::require_positive(options.offset_duration, fn, "offset_duration");
    const UniformSegment& first = out.segments.front();
    const Eigen::Index length = std::clamp<Eigen::Index>(
        static_cast<Eigen::Index>(std::llround(options.offset_duration / options.sample_time)), 1,
        first.rows());
    for (const Eigen::Index c : options.offset_columns) {
      out.offsets[c] =
          estimate_offset(first.data.col(c), OffsetWindow{0, length, options.offset_estimator});
      for (auto& segment : out.segments) segment.data.col(c).array() -= out.offsets[c];
    }
  }
  return out;
}

}  // namespace endohaptics::identification
