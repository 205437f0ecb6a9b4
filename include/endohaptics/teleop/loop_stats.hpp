//! @file
//! LoopStats: the figures of worksheet table 3.1 (achieved rate, period jitter, round-trip delay,
//! packet loss), online, O(1) memory and allocation-free: Welford mean/variance plus fixed-width
//! histograms (1 us bins) for percentiles. Times in seconds unless a name says otherwise.
#pragma once

#include <algorithm>
#include <array>
#include <chrono>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <limits>
#include <string>

namespace endohaptics::teleop {

//! Online summary of one duration signal (a period or a round trip), in seconds.
//! `Bins` histogram bins of `bin_width_ns` each; larger values fall into an overflow bin and
//! still count in mean, std and max (the p99 then reports the histogram's upper edge as a bound).
template <int Bins = 5000, std::int64_t BinWidthNs = 1000>
class DurationStats {
  static_assert(Bins >= 10, "a histogram needs a few bins");
  static_assert(BinWidthNs > 0);

 public:
  void add(std::chrono::nanoseconds d) noexcept {
    const auto ns = d.count();
    const double s = static_cast<double>(ns) * 1e-9;
    ++count_;
    const double delta = s - mean_;
    mean_ += delta / static_cast<double>(count_);
    m2_ += delta * (s - mean_);
    min_ = std::min(min_, s);
    max_ = std::max(max_, s);
    const std::int64_t bin = ns < 0 ? 0 : ns / BinWidthNs;
    if (bin >= Bins) {
      ++overflow_;
    } else {
      ++histogram_[static_cast<std::size_t>(bin)];
    }
  }

  [[nodiscard]] std::uint64_t count() const noexcept { return count_; }
  [[nodiscard]] double mean() const noexcept { return count_ ? mean_ : 0.0; }
  //! Sample standard deviation (n - 1).
  [[nodiscard]] double stddev() const noexcept {
    return count_ > 1 ? std::sqrt(m2_ / static_cast<double>(count_ - 1)) : 0.0;
  }
  [[nodiscard]] double min() const noexcept { return count_ ? min_ : 0.0; }
  [[nodiscard]] double max() const noexcept { return count_ ? max_ : 0.0; }
  //! Upper edge of the histogram bin holding quantile q in [0, 1] (resolution BinWidthNs),
  //! capped by the largest value seen.
  [[nodiscard]] double quantile(double q) const noexcept {
    if (count_ == 0) return 0.0;
    q = std::clamp(q, 0.0, 1.0);
    const auto target = static_cast<std::uint64_t>(std::ceil(q * static_cast<double>(count_)));
    std::uint64_t seen = 0;
    for (int i = 0; i < Bins; ++i) {
      seen += histogram_[static_cast<std::size_t>(i)];
      if (seen >= target && seen > 0) {
        return std::min(static_cast<double>((i + 1) * BinWidthNs) * 1e-9, max_);
      }
    }
    return max_;  // in the overflow bin: the largest value seen bounds it
  }
  [[nodiscard]] std::uint64_t overflow() const noexcept { return overflow_; }
  [[nodiscard]] const std::array<std::uint32_t, static_cast<std::size_t>(Bins)>& histogram()
      const noexcept {
    return histogram_;
  }
  static constexpr double bin_width() noexcept { return static_cast<double>(BinWidthNs) * 1e-9; }
  void reset() noexcept { *this = DurationStats{}; }

 private:
  std::uint64_t count_ = 0;
  double mean_ = 0.0;
  double m2_ = 0.0;
  double min_ = std::numeric_limits<double>::infinity();
  double max_ = 0.0;
  std::uint64_t overflow_ = 0;
  std::array<std::uint32_t, static_cast<std::size_t>(Bins)> histogram_{};
};

//! What happened in one tick, as reported by the loop.
enum class TickOutcome : std::uint8_t {
  received,        //!< a valid state packet arrived before the deadline
  timeout,         //!< nothing arrived before the deadline (a miss)
  decode_error,    //!< a datagram arrived but the codec rejected it (also a miss)
  transport_error  //!< send or receive failed at the OS level (also a miss)
};

//! Loop statistics: the worksheet's table 3.1 and more. One `record_*` per tick, all noexcept.
class LoopStats {
 public:
  using Clock = std::chrono::steady_clock;

  //! Nominal period, for deadline-miss counting and the period-error figures.
  explicit LoopStats(
      std::chrono::nanoseconds nominal_period = std::chrono::milliseconds(1)) noexcept
      : nominal_(nominal_period) {}

  //! Start of a tick at time `t` (the loop's clock). Periods are measured start to start.
  void record_tick_start(std::chrono::nanoseconds t) noexcept {
    if (ticks_ > 0) {
      const auto period = t - last_start_;
      period_.add(period);
      if (nominal_.count() > 0) {  // a nominal period of 0 means "as fast as possible"
        period_error_.add(period > nominal_ ? period - nominal_ : nominal_ - period);
        if (period > nominal_ + nominal_ / 10) ++deadline_misses_;
      }
    }
    if (ticks_ == 0) first_start_ = t;
    last_start_ = t;
    ++ticks_;
  }

  //! Outcome of the tick's exchange; `round_trip` is send -> receive (only for `received`).
  void record_exchange(TickOutcome outcome, std::chrono::nanoseconds round_trip,
                       std::size_t stale_dropped) noexcept {
    stale_dropped_ += stale_dropped;
    switch (outcome) {
      case TickOutcome::received:
        ++received_;
        round_trip_.add(round_trip);
        break;
      case TickOutcome::timeout:
        ++timeouts_;
        break;
      case TickOutcome::decode_error:
        ++decode_errors_;
        break;
      case TickOutcome::transport_error:
        ++transport_errors_;
        break;
    }
  }

  //! Time spent computing in the tick (everything except waiting), for the compute budget.
  void record_compute(std::chrono::nanoseconds compute) noexcept { compute_.add(compute); }

  [[nodiscard]] std::uint64_t ticks() const noexcept { return ticks_; }
  [[nodiscard]] std::uint64_t received() const noexcept { return received_; }
  [[nodiscard]] std::uint64_t timeouts() const noexcept { return timeouts_; }
  [[nodiscard]] std::uint64_t decode_errors() const noexcept { return decode_errors_; }
  [[nodiscard]] std::uint64_t transport_errors() const noexcept { return transport_errors_; }
  [[nodiscard]] std::uint64_t stale_dropped() const noexcept { return stale_dropped_; }
  [[nodiscard]] std::uint64_t deadline_misses() const noexcept { return deadline_misses_; }
  [[nodiscard]] std::uint64_t exchanges() const noexcept {
    return received_ + timeouts_ + decode_errors_ + transport_errors_;
  }
  //! Percentage of exchanges without a valid state packet (table 3.1's "packet loss").
  [[nodiscard]] double loss_percent() const noexcept {
    const auto n = exchanges();
    return n ? 100.0 * static_cast<double>(n - received_) / static_cast<double>(n) : 0.0;
  }
  //! Achieved rate (Hz) from the first to the last tick start.
  [[nodiscard]] double rate() const noexcept {
    if (ticks_ < 2) return 0.0;
    const double span = std::chrono::duration<double>(last_start_ - first_start_).count();
    return span > 0 ? static_cast<double>(ticks_ - 1) / span : 0.0;
  }
  [[nodiscard]] const DurationStats<>& period() const noexcept { return period_; }
  //! |period - nominal|: the period error the user feels as jitter.
  [[nodiscard]] const DurationStats<>& period_error() const noexcept { return period_error_; }
  [[nodiscard]] const DurationStats<>& round_trip() const noexcept { return round_trip_; }
  [[nodiscard]] const DurationStats<>& compute() const noexcept { return compute_; }
  [[nodiscard]] std::chrono::nanoseconds nominal_period() const noexcept { return nominal_; }

  void reset() noexcept { *this = LoopStats{nominal_}; }

  //! Table 3.1 layout plus percentiles. Not for the tick (allocates the string).
  [[nodiscard]] std::string to_table() const {
    char buf[1024];
    const auto us = [](double s) { return s * 1e6; };
    char nominal_buf[32];
    std::snprintf(nominal_buf, sizeof nominal_buf, "%.1f Hz",
                  nominal_.count() > 0 ? 1e9 / static_cast<double>(nominal_.count()) : 0.0);
    const std::string nominal = nominal_.count() > 0 ? nominal_buf : "as fast as possible";
    const int n = std::snprintf(
        buf, sizeof buf,
        "rate        %10.1f Hz   (nominal %s)\n"
        "period      mean %8.1f us  std %7.2f us  p99 %7.1f us  max %8.1f us\n"
        "period err  mean %8.2f us  p99 %7.1f us  max %8.1f us  deadline misses %llu\n"
        "round trip  mean %8.1f us  std %7.2f us  p99 %7.1f us  max %8.1f us\n"
        "compute     mean %8.2f us  p99 %7.1f us  max %8.1f us\n"
        "packets     %llu ticks, %llu received, loss %.3f %% (timeouts %llu, decode errors "
        "%llu, transport errors %llu), stale dropped %llu\n",
        rate(), nominal.c_str(), us(period_.mean()), us(period_.stddev()),
        us(period_.quantile(0.99)), us(period_.max()), us(period_error_.mean()),
        us(period_error_.quantile(0.99)), us(period_error_.max()),
        static_cast<unsigned long long>(deadline_misses_), us(round_trip_.mean()),
        us(round_trip_.stddev()), us(round_trip_.quantile(0.99)), us(round_trip_.max()),
        us(compute_.mean()), us(compute_.quantile(0.99)), us(compute_.max()),
        static_cast<unsigned long long>(ticks_), static_cast<unsigned long long>(received_),
        loss_percent(), static_cast<unsigned long long>(timeouts_),
        static_cast<unsigned long long>(decode_errors_),
        static_cast<unsigned long long>(transport_errors_),
        static_cast<unsigned long long>(stale_dropped_));
    return std::string(buf, n > 0 ? static_cast<std::size_t>(std::min<int>(n, sizeof buf - 1)) : 0);
  }

 private:
  std::chrono::nanoseconds nominal_;
  std::chrono::nanoseconds first_start_{0};
  std::chrono::nanoseconds last_start_{0};
  std::uint64_t ticks_ = 0;
  std::uint64_t received_ = 0;
  std::uint64_t timeouts_ = 0;
  std::uint64_t decode_errors_ = 0;
  std::uint64_t transport_errors_ = 0;
  std::uint64_t stale_dropped_ = 0;
  std::uint64_t deadline_misses_ = 0;
  DurationStats<> period_;
  DurationStats<> period_error_;
  DurationStats<> round_trip_;
  DurationStats<> compute_;
};

}  // namespace endohaptics::teleop
