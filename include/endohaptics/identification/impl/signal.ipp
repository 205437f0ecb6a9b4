//! @file
//! Function bodies of identification/signal.hpp: included at its end (header-only, the default), or
//! compiled once with ENDOHAPTICS_SEPARATE_COMPILATION (core/separate_compilation.hpp).
#pragma once

#include "endohaptics/identification/signal.hpp"

namespace endohaptics::identification {
namespace detail::signal {

ENDOHAPTICS_DECL std::string format(double value) {
  std::ostringstream out;
  out.precision(std::numeric_limits<double>::max_digits10);
  out << value;
  return out.str();
}

ENDOHAPTICS_DECL void fail(std::string_view function, const std::string& what) {
  ENDOHAPTICS_THROW(Error(std::string(function) + ": " + what));
}

ENDOHAPTICS_DECL void require_positive(double value, std::string_view function,
                                       std::string_view name) {
  if (!std::isfinite(value) || !(value > 0)) {
    fail(function, std::string(name) + " must be finite and > 0, got " + format(value));
  }
}

ENDOHAPTICS_DECL void require_increasing(const Eigen::Ref<const Eigen::VectorXd>& time,
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
}  // namespace endohaptics::identification

namespace endohaptics::identification {

ENDOHAPTICS_DECL double median_step(const Eigen::Ref<const Eigen::VectorXd>& time) {
  std::vector<double> steps;
  steps.reserve(static_cast<std::size_t>(std::max<Eigen::Index>(time.size() - 1, 0)));
  for (Eigen::Index k = 1; k < time.size(); ++k) steps.push_back(time[k] - time[k - 1]);
  return detail::signal::median(std::move(steps));
}

ENDOHAPTICS_DECL Segments resample_uniform(const Eigen::Ref<const Eigen::VectorXd>& time,
                                           const Eigen::Ref<const Eigen::MatrixXd>& signals,
                                           double ts, const ResampleOptions& options) {
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

ENDOHAPTICS_DECL Eigen::VectorXd differentiate(const Eigen::Ref<const Eigen::VectorXd>& time,
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

ENDOHAPTICS_DECL Eigen::VectorXd central_difference(const Eigen::Ref<const Eigen::VectorXd>& x,
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

ENDOHAPTICS_DECL Eigen::VectorXd savgol_filter(const Eigen::Ref<const Eigen::VectorXd>& x,
                                               int window, int polyorder, int deriv, double ts) {
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

ENDOHAPTICS_DECL SosMatrix butterworth_lowpass(int order, double cutoff, double ts) {
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

ENDOHAPTICS_DECL Eigen::Matrix<double, Eigen::Dynamic, 2> sosfilt_zi(const SosMatrix& sos) {
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

ENDOHAPTICS_DECL Eigen::VectorXd sosfilt(const SosMatrix& sos,
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

ENDOHAPTICS_DECL Eigen::Index filtfilt_padlen(const SosMatrix& sos) {
  const auto b2_zero = (sos.col(2).array() == 0.0).count();
  const auto a2_zero = (sos.col(5).array() == 0.0).count();
  return 3 * (2 * sos.rows() + 1 - std::min(b2_zero, a2_zero));
}

ENDOHAPTICS_DECL Eigen::VectorXd filtfilt(const SosMatrix& sos,
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

ENDOHAPTICS_DECL Eigen::MatrixXd filtfilt_columns(const SosMatrix& sos,
                                                  const Eigen::Ref<const Eigen::MatrixXd>& x) {
  Eigen::MatrixXd y(x.rows(), x.cols());
  for (Eigen::Index c = 0; c < x.cols(); ++c) y.col(c) = filtfilt(sos, x.col(c));
  return y;
}

ENDOHAPTICS_DECL double estimate_offset(const Eigen::Ref<const Eigen::VectorXd>& x,
                                        const OffsetWindow& window) {
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

ENDOHAPTICS_DECL double remove_offset(Eigen::Ref<Eigen::VectorXd> x, const OffsetWindow& window) {
  const double offset = estimate_offset(x, window);
  x.array() -= offset;
  return offset;
}

ENDOHAPTICS_DECL Eigen::VectorXd detrend(const Eigen::Ref<const Eigen::VectorXd>& x,
                                         DetrendType type) {
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

ENDOHAPTICS_DECL Segments preprocess(const Eigen::Ref<const Eigen::VectorXd>& time,
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
