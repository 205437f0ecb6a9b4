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
#include "endohaptics/core/separate_compilation.hpp"

#include "endohaptics/core/error.hpp"
#include "endohaptics/core/median.hpp"

namespace endohaptics::identification {

namespace detail::signal {

//! Round-trip formatting of a number for error messages.
ENDOHAPTICS_DECL std::string format(double value);

[[noreturn]] ENDOHAPTICS_DECL void fail(std::string_view function, const std::string& what);

ENDOHAPTICS_DECL void require_positive(double value, std::string_view function,
                                       std::string_view name);

using endohaptics::detail::median;

//! Throws unless `time` is finite and strictly increasing.
ENDOHAPTICS_DECL void require_increasing(const Eigen::Ref<const Eigen::VectorXd>& time,
                                         std::string_view function);

}  // namespace detail::signal

// ---------------------------------------------------------------------------------------------
// Time steps and resampling

//! Median of the time steps (s); NaN for fewer than two samples.
[[nodiscard]] ENDOHAPTICS_DECL double median_step(const Eigen::Ref<const Eigen::VectorXd>& time);

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
[[nodiscard]] ENDOHAPTICS_DECL Segments resample_uniform(
    const Eigen::Ref<const Eigen::VectorXd>& time, const Eigen::Ref<const Eigen::MatrixXd>& signals,
    double ts, const ResampleOptions& options = {});

// ---------------------------------------------------------------------------------------------
// Differentiators

//! Derivative on the source time stamps: the secant over the two neighbours,
//! (x[k+1] - x[k-1]) / (t[k+1] - t[k-1]), one-sided at both ends and next to steps > max_gap;
//! 0 for a sample isolated between two gaps. On a uniform grid this is the central difference.
//! Throws Error when sizes differ or time is not finite and strictly increasing.
[[nodiscard]] ENDOHAPTICS_DECL Eigen::VectorXd differentiate(
    const Eigen::Ref<const Eigen::VectorXd>& time, const Eigen::Ref<const Eigen::VectorXd>& x,
    double max_gap);

//! Central difference on a uniform grid, (x[k+1] - x[k-1]) / (2 ts), one-sided first
//! differences at the ends (numpy.gradient(x, ts) with edge_order=1). Precondition: ts > 0.
//! Throws Error for ts <= 0 or fewer than 2 samples.
[[nodiscard]] ENDOHAPTICS_DECL Eigen::VectorXd central_difference(
    const Eigen::Ref<const Eigen::VectorXd>& x, double ts);

//! Savitzky-Golay filter: at each sample the `deriv`-th derivative of the least-squares
//! polynomial of degree `polyorder` over `window` samples centred on it; the first and last
//! window/2 samples use the polynomial of the first/last full window (scipy.signal.savgol_filter
//! with mode='interp'). Divided by ts^deriv. Throws Error unless window is odd and <= x.size(),
//! 0 <= polyorder < window, 0 <= deriv, ts > 0.
[[nodiscard]] ENDOHAPTICS_DECL Eigen::VectorXd savgol_filter(
    const Eigen::Ref<const Eigen::VectorXd>& x, int window, int polyorder, int deriv = 0,
    double ts = 1.0);

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
[[nodiscard]] ENDOHAPTICS_DECL SosMatrix butterworth_lowpass(int order, double cutoff, double ts);

//! Initial state of each section for a unit step in steady state (scipy.signal.sosfilt_zi),
//! one row per section, transposed direct form II.
[[nodiscard]] ENDOHAPTICS_DECL Eigen::Matrix<double, Eigen::Dynamic, 2> sosfilt_zi(
    const SosMatrix& sos);

//! Runs the cascade over `x` (transposed direct form II, scipy.signal.sosfilt) from state `zi`
//! (one row per section; updated to the final state). Throws Error unless every section is
//! finite with a0 = 1 and zi has one row per section.
[[nodiscard]] ENDOHAPTICS_DECL Eigen::VectorXd sosfilt(
    const SosMatrix& sos, const Eigen::Ref<const Eigen::VectorXd>& x,
    Eigen::Matrix<double, Eigen::Dynamic, 2>& zi);

//! Padding `filtfilt` adds at each end: 3 (2 sections + 1 - sections with b2 = a2 = 0),
//! scipy.signal.sosfiltfilt's default.
[[nodiscard]] ENDOHAPTICS_DECL Eigen::Index filtfilt_padlen(const SosMatrix& sos);

//! Zero-phase filtering (scipy.signal.sosfiltfilt, padtype 'odd'): odd extension by
//! `filtfilt_padlen` samples at each end, forward pass from the steady state of the first
//! sample, backward pass from the steady state of the last output, extension removed.
//! Magnitude response |H|^2, no delay. Throws Error unless x.size() > filtfilt_padlen(sos).
[[nodiscard]] ENDOHAPTICS_DECL Eigen::VectorXd filtfilt(const SosMatrix& sos,
                                                        const Eigen::Ref<const Eigen::VectorXd>& x);

//! `filtfilt` applied to every column.
[[nodiscard]] ENDOHAPTICS_DECL Eigen::MatrixXd filtfilt_columns(
    const SosMatrix& sos, const Eigen::Ref<const Eigen::MatrixXd>& x);

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
[[nodiscard]] ENDOHAPTICS_DECL double estimate_offset(const Eigen::Ref<const Eigen::VectorXd>& x,
                                                      const OffsetWindow& window = {});

//! Subtracts the offset of `window` from all of `x` and returns it.
ENDOHAPTICS_DECL double remove_offset(Eigen::Ref<Eigen::VectorXd> x,
                                      const OffsetWindow& window = {});

//! What `detrend` removes.
enum class DetrendType : std::uint8_t {
  constant,  //!< the mean
  linear,    //!< the least-squares straight line over the sample index
};

//! x minus its mean or least-squares line (scipy.signal.detrend). Throws Error for an empty x.
[[nodiscard]] ENDOHAPTICS_DECL Eigen::VectorXd detrend(const Eigen::Ref<const Eigen::VectorXd>& x,
                                                       DetrendType type = DetrendType::linear);

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
[[nodiscard]] ENDOHAPTICS_DECL Segments preprocess(const Eigen::Ref<const Eigen::VectorXd>& time,
                                                   const Eigen::Ref<const Eigen::MatrixXd>& signals,
                                                   const PreprocessOptions& options);

}  // namespace endohaptics::identification

#if !defined(ENDOHAPTICS_SEPARATE_COMPILATION)
#include "endohaptics/identification/impl/signal.ipp"
#endif
